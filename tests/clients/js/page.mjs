// In the page: load glTF files with three.js's GLTFLoader, play clips with AnimationMixer and read
// the skinned vertex positions (SkinnedMesh.getVertexPosition, in world space: what is drawn).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

function base64(array) {
    const bytes = new Uint8Array(array.buffer);
    let text = '';
    for (let i = 0; i < bytes.length; i += 0x8000)
        text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(text);
}

// job: {url, poses: [[clip name or null for the rest pose, time], ...]}
// -> {meshes, vertices, positions: base64 float64 (poses, vertices, 3), clips: [names]}
async function skinPositions(job) {
    const gltf = await new GLTFLoader().loadAsync(job.url);
    const scene = gltf.scene;
    const meshes = [];
    scene.traverse((object) => { if (object.isMesh) meshes.push(object); });  // primitives in file order
    const n = meshes.reduce((sum, mesh) => sum + mesh.geometry.attributes.position.count, 0);
    const out = new Float64Array(job.poses.length * n * 3);
    const v = new THREE.Vector3();
    let k = 0;
    const read = () => {
        scene.updateMatrixWorld(true);
        for (const mesh of meshes) {
            for (let i = 0; i < mesh.geometry.attributes.position.count; i++) {
                mesh.getVertexPosition(i, v).applyMatrix4(mesh.matrixWorld);
                out[k++] = v.x; out[k++] = v.y; out[k++] = v.z;
            }
        }
    };
    let mixer = null, action = null, playing = null;
    for (const [name, time] of job.poses) {
        if (name !== playing && action) {  // back to the rest pose: the mixer restores what it bound
            action.stop();
            mixer.uncacheRoot(scene);
            action = null;
        }
        if (name !== null && action === null) {
            const clip = THREE.AnimationClip.findByName(gltf.animations, name);
            if (!clip) throw new Error(`${job.url}: no clip ${name}`);
            mixer = new THREE.AnimationMixer(scene);
            action = mixer.clipAction(clip);
            action.setLoop(THREE.LoopOnce, 1);
            action.clampWhenFinished = true;  // glTF holds the last key after the end
        }
        playing = name;
        if (action) {
            action.reset().play();
            mixer.setTime(time);
        }
        read();
    }
    return {meshes: meshes.length, vertices: n, positions: base64(out),
            clips: gltf.animations.map((clip) => clip.name)};
}

window.skinPositions = async (jobs) => {
    const results = [];
    for (const job of jobs) {
        try {
            results.push(await skinPositions(job));
        } catch (error) {
            results.push({error: String(error && error.stack || error)});
        }
    }
    return results;
};
window.ready = true;
