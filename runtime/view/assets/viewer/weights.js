// Vertex colours by one joint's skin weight, Blender's weight-paint ramp: 0 blue, 0.25 cyan,
// 0.5 green, 0.75 yellow, 1 red. Vertices the joint does not influence at all are grey, so that
// "weight 0 but listed" (blue) and "not a bone of this vertex" can be told apart.
import * as THREE from 'three';

const RAMP = [[0, 0, 1], [0, 1, 1], [0, 1, 0], [1, 1, 0], [1, 0, 0]];
export const NOT_INFLUENCED = [0.35, 0.35, 0.35];

export function ramp(weight) {
    const x = Math.min(Math.max(weight, 0), 1) * (RAMP.length - 1);
    const i = Math.min(Math.floor(x), RAMP.length - 2), f = x - i;
    return RAMP[i].map((a, k) => a + (RAMP[i + 1][k] - a) * f);
}

// The (n, 3) colour attribute of `mesh` for bone index `bone` of its skeleton (linear colours: the
// ramp is given in sRGB, as Blender shows it), and how many vertices the bone influences.
export function weightColors(mesh, bone) {
    const index = mesh.geometry.attributes.skinIndex, weight = mesh.geometry.attributes.skinWeight;
    const colors = new Float32Array(index.count * 3);
    const color = new THREE.Color();
    let count = 0;
    for (let v = 0; v < index.count; v++) {
        let w = 0, influenced = false;
        for (let k = 0; k < 4; k++) {
            if (index.getComponent(v, k) === bone && weight.getComponent(v, k) > 0) {
                w += weight.getComponent(v, k);
                influenced = true;
            }
        }
        if (influenced) count++;
        const rgb = influenced ? ramp(w) : NOT_INFLUENCED;
        color.setRGB(rgb[0], rgb[1], rgb[2], THREE.SRGBColorSpace);
        colors[3 * v] = color.r; colors[3 * v + 1] = color.g; colors[3 * v + 2] = color.b;
    }
    return {colors: new THREE.BufferAttribute(colors, 3), influenced: count};
}

// Show the weights of the bone named `name` on every skinned mesh (null: the model's own colours).
// Returns the number of vertices the bone influences.
export function showWeights(meshes, name) {
    let influenced = 0;
    for (const mesh of meshes) {
        const geometry = mesh.geometry;
        if (geometry.userData.ownColor === undefined)
            geometry.userData.ownColor = geometry.attributes.color || null;
        const bone = name === null ? -1 : mesh.skeleton.bones.findIndex((b) => b.name === name);
        if (bone < 0) {
            if (geometry.userData.ownColor) geometry.setAttribute('color', geometry.userData.ownColor);
            else geometry.deleteAttribute('color');
            mesh.material.vertexColors = Boolean(geometry.userData.ownColor);
            mesh.material.map = mesh.material.userData.map || null;
            if (mesh.material.userData.color) mesh.material.color.copy(mesh.material.userData.color);
        } else {
            const {colors, influenced: count} = weightColors(mesh, bone);
            geometry.setAttribute('color', colors);
            influenced += count;
            mesh.material.userData.map = mesh.material.userData.map || mesh.material.map;
            mesh.material.map = null;    // (the texture would tint the ramp)
            mesh.material.vertexColors = true;
            mesh.material.userData.color = mesh.material.userData.color || mesh.material.color.clone();
            mesh.material.color.set(0xffffff);   // (the ramp's colours as they are, only lit)
        }
        mesh.material.needsUpdate = true;
    }
    return influenced;
}
