// cgaskin's own skinning in the page: the skinning mode "cgaskin".
//
// Each frame, every bone's global transform is composed as a versor from the local TRS the clip set
// on it and on its ancestors (T R D per node, the generated kernels of cgaskin_kernels.js in float64:
// what cgaskin's sampling does in numba), and written to a float texture beside a constant map applied
// first (the bone's inverse bind matrix times the mesh's bind matrix). The vertex shader runs the
// generated GLSL ES chunk (cgaskin_skin_webgl.glsl): versor -> affine per influence, then the blend,
// in place of three.js's bone matrices. A bone whose chain holds a non-uniform scale has no versor:
// it gets the identity versor and its whole map in the second slot (exact, as cgaskin's matrix nodes).
//
// readSkinnedPositions reads what a skinning mode's vertex shader computes back from the GPU (each
// vertex drawn as a point into its own texel of a float render target), for either mode: the tests
// compare the two.
import * as THREE from 'three';
import { cgaskin_versor_translator as translator, cgaskin_versor_rotor_quaternion as rotor,
         cgaskin_versor_dilator as dilator, cgaskin_gp_versor_versor as product } from 'cgaskin/kernels.js';
import CHUNK from 'cgaskin/skin_webgl.js';

const TEXELS_PER_BONE = 6;                   // versor (12 floats), then the map applied first (3x4)
const IDENTITY = Float64Array.of(1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);

// The node's local versor T R D (D: its uniform scale times the page's dilation of it), or null when
// its scale is not uniform and positive (no versor holds it).
function localVersor(node) {
    const s = node.scale, q = node.quaternion, p = node.position;
    if (!(s.x === s.y && s.y === s.z && s.x > 0)) return null;
    const scale = s.x * (node.userData.dilation ?? 1);
    const motion = product(translator([p.x, p.y, p.z]), rotor([q.x, q.y, q.z, q.w]));
    return scale === 1 ? motion : product(motion, dilator(scale));
}

// Rows 0..2 of a Matrix4 (three stores columns) into out[at..at+12), row-major 3x4.
function writeRows(matrix, out, at) {
    const e = matrix.elements;
    for (let r = 0; r < 3; r++)
        for (let c = 0; c < 4; c++) out[at + 4 * r + c] = e[4 * c + r];
}

export class CgaskinSkinning {
    constructor(mesh) {
        this.mesh = mesh;
        this.bones = mesh.skeleton.bones;
        const texels = TEXELS_PER_BONE * Math.max(this.bones.length, 1);
        const width = Math.min(texels, 1024 * TEXELS_PER_BONE);
        const height = Math.ceil(texels / width);
        this.data = new Float32Array(width * height * 4);
        this.texture = new THREE.DataTexture(this.data, width, height, THREE.RGBAFormat, THREE.FloatType);
        // the map each bone applies first: its inverse bind matrix after the mesh's bind matrix
        this.first = this.bones.map((bone, b) => new THREE.Matrix4().multiplyMatrices(
            mesh.skeleton.boneInverses[b], mesh.bindMatrix));
        this.uniforms = {cgaskin_bones: {value: this.texture}, cgaskin_bone_count: {value: this.bones.length}};
        this.update();
    }

    // The bones' versors of the current pose into the texture (call after the clip or an edit moved them).
    update() {
        const world = new Map();                 // node -> its global versor, or null (not a similarity)
        const globalVersor = (node) => {
            if (!node) return IDENTITY;
            if (world.has(node)) return world.get(node);
            const parent = globalVersor(node.parent), local = localVersor(node);
            const versor = parent && local ? product(parent, local) : null;
            world.set(node, versor);
            return versor;
        };
        const whole = new THREE.Matrix4();
        this.bones.forEach((bone, b) => {
            const at = TEXELS_PER_BONE * 4 * b, versor = globalVersor(bone);
            if (versor) {
                this.data.set(versor, at);
                writeRows(this.first[b], this.data, at + 12);
            } else {
                this.data.set(IDENTITY, at);
                bone.updateWorldMatrix(true, false);
                writeRows(whole.multiplyMatrices(bone.matrixWorld, this.first[b]), this.data, at + 12);
            }
        });
        this.texture.needsUpdate = true;
    }
}

// The vertex shader's text with three.js's skinning chunks replaced by cgaskin's: the blended map
// moves the position (skinning_vertex) and the normal and tangent (skinnormal_vertex).
export function cgaskinVertexShader(source) {
    const blend = 'float cgaskin_map[12]; cgaskin_blend(skinIndex, skinWeight, cgaskin_map);';
    const replaced = source
        .replace('#include <skinning_pars_vertex>', `#include <skinning_pars_vertex>\n#ifdef USE_SKINNING\n${CHUNK}\n#endif`)
        .replace('#include <skinbase_vertex>', '')
        .replace('#include <skinnormal_vertex>', `#ifdef USE_SKINNING
    {
        ${blend}
        objectNormal = (bindMatrixInverse * vec4(cgaskin_apply_direction(cgaskin_map, objectNormal), 0.0)).xyz;
        #ifdef USE_TANGENT
        objectTangent = (bindMatrixInverse * vec4(cgaskin_apply_direction(cgaskin_map, objectTangent), 0.0)).xyz;
        #endif
    }
#endif`)
        .replace('#include <skinning_vertex>', `#ifdef USE_SKINNING
    {
        ${blend}
        transformed = (bindMatrixInverse * vec4(cgaskin_apply_point(cgaskin_map, transformed), 1.0)).xyz;
    }
#endif`);
    if (!replaced.includes('cgaskin_apply_point')) throw new Error('three.js shader without <skinning_vertex>');
    return replaced;
}

// Let `material` (of `mesh`) skin with cgaskin's shader; returns the CgaskinSkinning to update per frame.
export function useCgaskinSkinning(material, mesh) {
    const skinning = new CgaskinSkinning(mesh);
    material.onBeforeCompile = (shader) => {
        Object.assign(shader.uniforms, skinning.uniforms);
        shader.vertexShader = cgaskinVertexShader(shader.vertexShader);
    };
    material.customProgramCacheKey = () => 'cgaskin-skinning';
    material.needsUpdate = true;
    return skinning;
}

// What the vertex stage of `mode` ("three" or "cgaskin") puts in `transformed` for every vertex of
// `mesh` in its current pose, read back from the GPU: (n, 3) Float32Array, mesh space (before the
// mesh's own world matrix, as SkinnedMesh.getVertexPosition). `skinning`: the mesh's CgaskinSkinning.
export function readSkinnedPositions(renderer, mesh, mode, skinning) {
    const n = mesh.geometry.attributes.position.count;
    const width = Math.min(n, 1024), height = Math.ceil(n / width);
    const geometry = new THREE.BufferGeometry();
    for (const name of ['position', 'skinIndex', 'skinWeight'])
        geometry.setAttribute(name, mesh.geometry.attributes[name]);
    mesh.skeleton.update();
    const uniforms = {bindMatrix: {value: mesh.bindMatrix}, bindMatrixInverse: {value: mesh.bindMatrixInverse},
                      boneTexture: {value: mesh.skeleton.boneTexture}, cgaskin_width: {value: width},
                      cgaskin_height: {value: height}, ...(skinning ? skinning.uniforms : {})};
    let vertexShader = `
#define USE_SKINNING
#include <common>
#include <skinning_pars_vertex>
in vec4 skinIndex;
in vec4 skinWeight;
uniform int cgaskin_width;
uniform int cgaskin_height;
out vec3 cgaskin_skinned;
void main() {
    vec3 transformed = position;
    #include <skinbase_vertex>
    #include <skinning_vertex>
    cgaskin_skinned = transformed;
    int i = gl_VertexID;
    gl_Position = vec4((float(i % cgaskin_width) + 0.5) / float(cgaskin_width) * 2.0 - 1.0,
                       (float(i / cgaskin_width) + 0.5) / float(cgaskin_height) * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
}`;
    if (mode === 'cgaskin') vertexShader = cgaskinVertexShader(vertexShader);
    else if (mode !== 'three') throw new Error(`skinning mode ${JSON.stringify(mode)}: "three" or "cgaskin"`);
    const material = new THREE.ShaderMaterial({
        uniforms, vertexShader,
        fragmentShader: 'in vec3 cgaskin_skinned; out vec4 color; void main() { color = vec4(cgaskin_skinned, 1.0); }',
        glslVersion: THREE.GLSL3,
    });
    const points = new THREE.Points(geometry, material);
    points.frustumCulled = false;
    const scene = new THREE.Scene(), camera = new THREE.Camera();
    scene.add(points);
    const target = new THREE.WebGLRenderTarget(width, height, {type: THREE.FloatType, format: THREE.RGBAFormat,
                                                               depthBuffer: false});
    const pixels = new Float32Array(width * height * 4);
    const keep = renderer.getRenderTarget();
    try {
        renderer.setRenderTarget(target);
        renderer.render(scene, camera);
        renderer.readRenderTargetPixels(target, 0, 0, width, height, pixels);
    } finally {
        renderer.setRenderTarget(keep);
        target.dispose();
        material.dispose();
        geometry.dispose();
    }
    const out = new Float32Array(n * 3);
    for (let i = 0; i < n; i++) out.set(pixels.subarray(4 * i, 4 * i + 3), 3 * i);
    return out;
}
