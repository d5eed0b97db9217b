// cgaskin view: the page's entry module. It reads what Python embedded (the rig as a .glb in base64,
// and a JSON block: name, clip to start with, skinning mode, rim edges), loads the model with
// GLTFLoader from memory (no request), and wires the panel, the frame loop and window.cgaskinView,
// the page's small API for tests and notebooks.
//
// (The viewer's modules import one another by bare names, 'cgaskin/ui.js': the page turns every
// inlined module into a blob: URL through an import map, and a blob: URL is no base for './ui.js'.)
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { buildPanel, showDilation, showPlaying, showStatus, showTime } from 'cgaskin/ui.js';
import { SKINNING_MODES, createSkinnedMaterial, createView, frame, resize } from 'cgaskin/scene.js';
import { CgaskinSkinning, readSkinnedPositions } from 'cgaskin/cgaskin_skinning.js';
import { Playback, dilatable } from 'cgaskin/playback.js';
import { showWeights } from 'cgaskin/weights.js';
import { SkeletonView, hoverNames } from 'cgaskin/skeleton.js';
import { Rims } from 'cgaskin/rims.js';
import { startSurgery } from 'cgaskin/surgery.js';

function embedded() {
    const data = JSON.parse(document.getElementById('cgaskin-data').textContent);
    const text = atob(document.getElementById('cgaskin-model').textContent.trim());
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
    return [data, bytes.buffer];
}

function base64(array) {
    const bytes = new Uint8Array(array.buffer);
    let text = '';
    for (let i = 0; i < bytes.length; i += 0x8000)
        text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(text);
}

// The mesh's vertex count (cgaskin serve's buffers hold spare rows past it: mesh_delta.js).
const vertexCount = (mesh) => mesh.geometry.userData.vertexCount ?? mesh.geometry.attributes.position.count;

// World-space skinned positions of every vertex, meshes in file order: (n, 3) float64.
function skinnedPositions(meshes) {
    const n = meshes.reduce((sum, mesh) => sum + vertexCount(mesh), 0);
    const out = new Float64Array(n * 3), p = new THREE.Vector3();
    let k = 0;
    for (const mesh of meshes) {
        for (let i = 0; i < vertexCount(mesh); i++) {
            mesh.getVertexPosition(i, p).applyMatrix4(mesh.matrixWorld);
            out[k++] = p.x; out[k++] = p.y; out[k++] = p.z;
        }
    }
    return out;
}

async function start(container) {
    const [data, glb] = embedded();
    const gltf = await new GLTFLoader().parseAsync(glb, '');
    const root = gltf.scene;
    const meshes = [];
    root.traverse((object) => { if (object.isSkinnedMesh) meshes.push(object); });
    if (!meshes.length) throw new Error('the model has no skinned mesh');
    let skinningMode = data.skinning;
    for (const mesh of meshes) {
        mesh.userData.sourceMaterial = mesh.material;
        mesh.material = createSkinnedMaterial(mesh.material, skinningMode, mesh);
        mesh.frustumCulled = false;       // three culls skinned meshes by their bind-pose bounds
    }
    const bones = [...new Set(meshes.flatMap((mesh) => mesh.skeleton.bones))];
    const boneNames = bones.map((bone) => bone.name);

    const canvas = container.querySelector('canvas');
    const view = createView(canvas);
    view.scene.add(root);
    const playback = new Playback(root, gltf.animations);
    const skeleton = new SkeletonView(view.scene, root, bones, view.camera, canvas);
    const rims = new Rims(view.scene, meshes, data.rims);
    const dilations = new Map();          // bone name -> uniform scale factor (the algebra's dilator)
    for (const bone of bones) dilatable(bone);
    let dilateJoint = boneNames[0];

    const pose = (seconds) => {
        playback.advance(seconds);
        for (const bone of bones) bone.userData.dilation = dilations.get(bone.name) ?? 1;
        root.updateMatrixWorld(true);
        for (const mesh of meshes) mesh.material.userData.cgaskinSkinning?.update();
        rims.update();
        showTime(panel, playback.time, playback.duration);
        showPlaying(panel, playback.playing);
    };
    const render = () => {
        resize(view);
        view.renderer.render(view.scene, view.camera);
    };
    const redraw = () => { pose(0); render(); };
    const bone = (name) => {
        const found = boneNames.includes(name) ? name : THREE.PropertyBinding.sanitizeNodeName(name);
        if (!boneNames.includes(found))
            throw new Error(`no joint ${JSON.stringify(name)}; the joints: ${boneNames.join(', ')}`);
        return found;
    };

    const api = {
        clips: gltf.animations.map((clip) => ({name: clip.name, duration: clip.duration})),
        bones: boneNames,
        vertices: meshes.reduce((sum, mesh) => sum + mesh.geometry.attributes.position.count, 0),
        skinningModes: SKINNING_MODES,
        skinning() { return skinningMode; },
        setSkinning(mode) {
            if (!SKINNING_MODES.includes(mode))
                throw new Error(`skinning ${JSON.stringify(mode)}: one of ${SKINNING_MODES.join(', ')}`);
            skinningMode = mode;
            for (const mesh of meshes) {
                mesh.material.dispose();
                mesh.material = createSkinnedMaterial(mesh.userData.sourceMaterial, mode, mesh);
            }
            showWeights(meshes, panel.weightJoint.value || null);     // (on the new materials)
            panel.skinning.value = mode;
            redraw();
            return mode;
        },
        // What the vertex shader of a skinning mode computes for every vertex in the pose shown, read
        // back from the GPU: base64 of (n, 3) float64 (float32 values), world space, meshes in file order.
        shaderPositions(mode) {
            root.updateMatrixWorld(true);
            const parts = meshes.map((mesh) => {
                const skinning = mode === 'cgaskin' ? (mesh.material.userData.cgaskinSkinning || new CgaskinSkinning(mesh)) : null;
                const local = readSkinnedPositions(view.renderer, mesh, mode, skinning);
                const out = new Float64Array(local.length), p = new THREE.Vector3();
                for (let i = 0; i < local.length; i += 3) {
                    p.set(local[i], local[i + 1], local[i + 2]).applyMatrix4(mesh.matrixWorld);
                    out[i] = p.x; out[i + 1] = p.y; out[i + 2] = p.z;
                }
                return out;
            });
            const all = new Float64Array(parts.reduce((sum, part) => sum + part.length, 0));
            let at = 0;
            for (const part of parts) { all.set(part, at); at += part.length; }
            return base64(all);
        },
        setClip(name) { playback.setClip(name); panel.clip.value = name; redraw(); return name; },
        clip() { return playback.clip ? playback.clip.name : null; },
        play() { playback.playing = Boolean(playback.clip); redraw(); },
        pause() { playback.playing = false; redraw(); },
        isPlaying() { return playback.playing; },
        setTime(seconds) { playback.setTime(Number(seconds)); redraw(); return playback.time; },
        getTime() { return playback.time; },
        mixerTime() { return playback.mixer.time; },
        setSpeed(speed) { playback.speed = Number(speed); panel.speed.value = String(speed); },
        setLoop(loop) { playback.setLoop(loop); panel.loop.checked = Boolean(loop); },
        setWeightJoint(name) {
            const found = name === null ? null : bone(name);
            const influenced = showWeights(meshes, found);
            panel.weightJoint.value = found || '';
            redraw();
            return influenced;
        },
        setDilation(name, factor) {
            const found = bone(name);
            factor = Number(factor);
            if (!(factor > 0 && isFinite(factor))) throw new Error(`dilation ${factor}: give a factor > 0`);
            if (factor === 1) dilations.delete(found); else dilations.set(found, factor);
            dilateJoint = found;
            showDilation(panel, found, factor);
            redraw();
            return factor;
        },
        showSkeleton(on) { skeleton.visible = on; panel.skeleton.checked = Boolean(on); redraw(); },
        showRims(on) { rims.visible = on; panel.rims.checked = rims.visible; redraw(); },
        rimCount() { return rims.count; },
        rimPositions() { rims.update(); return base64(Float64Array.from(rims.lines.geometry.attributes.position.array)); },
        boneScreenPositions() { return skeleton.screenPositions(); },
        boneAt(x, y) { return skeleton.boneAt(x, y); },
        hoveredBone() { return panel.boneLabel.style.display === 'block' ? panel.boneLabel.textContent : null; },
        positions() { root.updateMatrixWorld(true); return base64(skinnedPositions(meshes)); },
        render() { redraw(); },
        snapshot() { redraw(); return canvas.toDataURL('image/png'); },
        frame() { frameModel(); redraw(); },
    };

    const panel = buildPanel(container, api.clips, boneNames, rims.count, SKINNING_MODES, skinningMode, {
        clip: (name) => api.setClip(name),
        play: () => (playback.playing ? api.pause() : api.play()),
        time: (seconds) => api.setTime(seconds),
        speed: (speed) => api.setSpeed(speed),
        loop: (loop) => api.setLoop(loop),
        skeleton: (on) => api.showSkeleton(on),
        weightJoint: (name) => api.setWeightJoint(name),
        dilateJoint: (name) => { dilateJoint = name; showDilation(panel, name, dilations.get(name) || 1); },
        dilation: (factor) => api.setDilation(dilateJoint, factor),
        rims: (on) => api.showRims(on),
        skinning: (mode) => api.setSkinning(mode),
        savePng: () => {
            const link = document.createElement('a');
            link.download = `${data.name || 'cgaskin'}.png`;
            link.href = api.snapshot();
            link.click();
        },
    });
    hoverNames(skeleton, canvas, panel.boneLabel);

    // Frame the model over its first clip (a clip may move it), in its bounds at 8 times.
    const frameModel = () => {
        const box = new THREE.Box3(), keep = playback.time, v = new THREE.Vector3();
        const times = playback.clip ? [...Array(8).keys()].map((i) => i / 7 * playback.duration) : [0];
        for (const t of times) {
            playback.setTime(t);
            pose(0);
            const p = skinnedPositions(meshes);
            for (let i = 0; i < p.length; i += 3) box.expandByPoint(v.set(p[i], p[i + 1], p[i + 2]));
        }
        playback.setTime(keep);
        resize(view);
        frame(view, box);
    };

    if (data.clip !== null) { playback.setClip(data.clip); panel.clip.value = data.clip; }
    playback.playing = Boolean(data.play && playback.clip);
    frameModel();
    if (data.time) playback.setTime(data.time);
    redraw();
    const clock = new THREE.Clock();
    view.renderer.setAnimationLoop(() => { pose(clock.getDelta()); render(); });
    // cgaskin serve: the surgery panel, the pointer's scalpel and the session's WebSocket
    if (data.serve) Object.assign(api, await startSurgery({container, canvas, view, meshes, playback, rims, panel,
                                                           dilations, redraw}));
    showStatus(panel, `${data.name}: ${api.vertices} vertices, ${boneNames.length} joints, ` +
                      `${api.clips.length} clips; skinning: ${skinningMode}`);
    return api;
}

const container = document.getElementById('cgaskin-view');
let resolveReady, rejectReady;
const ready = new Promise((resolve, reject) => { resolveReady = resolve; rejectReady = reject; });
window.cgaskinView = {ready};
start(container).then((api) => {
    Object.assign(window.cgaskinView, api);
    resolveReady(true);
}, (error) => {
    console.error(`cgaskin view: ${error && error.stack || error}`);
    const status = document.getElementById('status') || container;
    status.textContent = `cgaskin view could not show the model: ${error}`;
    rejectReady(error);
});
