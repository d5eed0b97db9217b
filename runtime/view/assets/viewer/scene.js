// Renderer, camera, lights, orbit controls, framing, and the skinned meshes' material.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { useCgaskinSkinning } from 'cgaskin/cgaskin_skinning.js';

export const BACKGROUND = 0x1d2026;

export function createView(canvas) {
    // preserveDrawingBuffer: "save PNG" (canvas.toDataURL) reads the last frame after it was shown
    const renderer = new THREE.WebGLRenderer({canvas, antialias: true, preserveDrawingBuffer: true});
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(BACKGROUND);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 2.0);
    sun.position.set(1, 2, 1.5);
    scene.add(sun);
    const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
    const controls = new OrbitControls(camera, canvas);
    controls.enableDamping = false;          // (a still picture between interactions: tests compare frames)
    return {renderer, scene, camera, controls, sun};
}

export function resize(view) {
    const canvas = view.renderer.domElement;
    const width = canvas.clientWidth || 640, height = canvas.clientHeight || 480;
    if (canvas.width !== Math.round(width * view.renderer.getPixelRatio()) ||
        canvas.height !== Math.round(height * view.renderer.getPixelRatio())) {
        view.renderer.setSize(width, height, false);
        view.camera.aspect = width / height;
        view.camera.updateProjectionMatrix();
    }
}

// Point the camera at the box (the skinned meshes' bounds in the poses shown) from the front and a
// little above, as near as keeps the whole box in view at the canvas's aspect.
export function frame(view, box) {
    const center = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
    const direction = new THREE.Vector3(0.55, 0.35, 1).normalize();
    // the nearest distance at which every corner of the box is inside both angles of view, plus 5 %
    const back = direction, right = new THREE.Vector3(0, 1, 0).cross(back).normalize();
    const up = back.clone().cross(right);
    const tanY = Math.tan(THREE.MathUtils.degToRad(view.camera.fov) / 2), tanX = tanY * view.camera.aspect;
    let distance = 1e-6;
    for (let i = 0; i < 8; i++) {
        const corner = new THREE.Vector3(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y,
                                         i & 4 ? box.max.z : box.min.z).sub(center);
        const z = corner.dot(back);
        distance = Math.max(distance, z + Math.abs(corner.dot(right)) / tanX, z + Math.abs(corner.dot(up)) / tanY);
    }
    distance *= 1.05;
    view.camera.position.copy(center).addScaledVector(direction, distance);
    view.camera.near = distance / 100;
    view.camera.far = distance * 100;
    view.camera.updateProjectionMatrix();
    view.controls.target.copy(center);
    view.controls.update();
    view.sun.position.copy(center).add(new THREE.Vector3(radius, 2 * radius, 1.5 * radius));
}

// The skinning modes the page knows: "cgaskin", the bones' versors blended by cgaskin's generated
// GLSL ES in the vertex shader (cgaskin_skinning.js), and "three", three.js's own matrix skinning.
export const SKINNING_MODES = ['cgaskin', 'three'];

// The one place where a skinned mesh's material is made. In the "cgaskin" mode the material's
// userData.cgaskinSkinning holds the bones' texture, to update after every pose.
export function createSkinnedMaterial(source, mode, mesh) {
    if (!SKINNING_MODES.includes(mode))
        throw new Error(`skinning mode ${JSON.stringify(mode)} is not one of ${SKINNING_MODES.join(', ')}`);
    const material = new THREE.MeshStandardMaterial({
        // (cgaskin's .glb carries no materials: a warm grey, unless the model brings a texture)
        color: source && source.map ? source.color.clone() : new THREE.Color(0xd9a27a),
        map: source && source.map ? source.map : null,
        roughness: 0.75,
        metalness: 0.0,
        side: THREE.DoubleSide,           // cut and torn meshes are open: their inside shows
        polygonOffset: true,              // the faces a little behind the rim lines drawn on them
        polygonOffsetFactor: 1,
        polygonOffsetUnits: 1,
    });
    material.userData.skinning = mode;
    if (mode === 'cgaskin') material.userData.cgaskinSkinning = useCgaskinSkinning(material, mesh);
    return material;
}
