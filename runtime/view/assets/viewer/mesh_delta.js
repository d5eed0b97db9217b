// cgaskin serve: the page's copy of the session's mesh, updated in place from the server's deltas
// (runtime/serve/delta.py) without loading the model again.
//
// The geometry GLTFLoader made has buffers of exactly the model's size. GrowableMesh gives every
// attribute the server updates a typed array with spare capacity (doubling when a delta outgrows it),
// so that a stroke writes its few rows and three.js uploads only those (addUpdateRange per run of
// consecutive rows); the faces live in slots of the index buffer (a freed slot holds the degenerate
// triangle 0, 0, 0) and the draw range covers the slots in use. geometry.userData.vertexCount is the
// session's vertex count (the buffers may be longer).
import * as THREE from 'three';

// what the server sends for each attribute (three.js name -> typed array of the base64 bytes)
const DECODERS = {position: Float32Array, skinIndex: Uint16Array, skinWeight: Float32Array, normal: Float32Array,
                  tangent: Float32Array, uv: Float32Array, uv1: Float32Array};

export function decode(text, Type) {
    const raw = atob(text), bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    return new Type(bytes.buffer);           // (the server sends little-endian: every browser's order)
}

// A copy of `attribute` as a `Type` array of `capacity` rows (normalised integers read as their values).
function grown(attribute, Type, capacity) {
    const array = new Type(capacity * attribute.itemSize), rows = Math.min(attribute.count, capacity);
    for (let i = 0; i < rows; i++)
        for (let k = 0; k < attribute.itemSize; k++) array[i * attribute.itemSize + k] = attribute.getComponent(i, k);
    const out = new THREE.BufferAttribute(array, attribute.itemSize);
    out.setUsage(THREE.DynamicDrawUsage);
    return out;
}

// One addUpdateRange per run of consecutive rows (rows sorted ascending), itemSize values each.
function markRows(attribute, rows) {
    attribute.needsUpdate = true;
    if (!attribute.updateRanges) return;
    const size = attribute.itemSize;
    for (let i = 0; i < rows.length;) {
        let j = i;
        while (j + 1 < rows.length && rows[j + 1] === rows[j] + 1) j++;
        attribute.addUpdateRange(rows[i] * size, (j - i + 1) * size);
        i = j + 1;
    }
}

export class GrowableMesh {
    constructor(mesh) {
        this.mesh = mesh;
        const geometry = mesh.geometry;
        // attributes the server does not send would fall behind the others: the page drops them
        for (const name of Object.keys(geometry.attributes))
            if (!(name in DECODERS)) geometry.deleteAttribute(name);
        const n = geometry.attributes.position.count;
        for (const name of Object.keys(geometry.attributes))
            geometry.setAttribute(name, grown(geometry.attributes[name], DECODERS[name], n));
        const index = geometry.index
            ? Uint32Array.from(geometry.index.array)
            : Uint32Array.from({length: n}, (_, i) => i);
        geometry.setIndex(new THREE.BufferAttribute(index, 1).setUsage(THREE.DynamicDrawUsage));
        geometry.userData.vertexCount = n;
        this.slots = index.length / 3;
        geometry.setDrawRange(0, 3 * this.slots);
    }

    get vertexCount() { return this.mesh.geometry.userData.vertexCount; }

    // Room for `rows` rows in every vertex attribute (doubling): new arrays are uploaded whole.
    _reserve(rows) {
        const geometry = this.mesh.geometry;
        for (const name of Object.keys(geometry.attributes)) {
            const attribute = geometry.attributes[name];
            if (attribute.count < rows)
                geometry.setAttribute(name, grown(attribute, DECODERS[name], Math.max(rows, 2 * attribute.count)));
        }
    }

    _reserveSlots(slots) {
        const geometry = this.mesh.geometry, index = geometry.index;
        if (index.count >= 3 * slots) return;
        const array = new Uint32Array(3 * Math.max(slots, 2 * index.count / 3));
        array.set(index.array);
        geometry.setIndex(new THREE.BufferAttribute(array, 1).setUsage(THREE.DynamicDrawUsage));
    }

    // Write a delta ({n_vertices, slots, rows: {index, <attribute>: base64}, faces: {slots, corners}}).
    // Returns the number of rows and face slots written.
    apply(delta) {
        const geometry = this.mesh.geometry;
        this._reserve(delta.n_vertices);
        const rows = decode(delta.rows.index, Uint32Array);
        for (const [name, text] of Object.entries(delta.rows)) {
            const attribute = geometry.attributes[name];
            if (name === 'index' || !attribute) continue;
            const values = decode(text, DECODERS[name]), size = attribute.itemSize;
            if (values.length !== rows.length * size)
                throw new Error(`delta: ${name} holds ${values.length} values for ${rows.length} rows of ${size}`);
            for (let k = 0; k < rows.length; k++)
                attribute.array.set(values.subarray(k * size, (k + 1) * size), rows[k] * size);
            markRows(attribute, rows);
        }
        this._reserveSlots(delta.slots);
        const slots = decode(delta.faces.slots, Uint32Array), corners = decode(delta.faces.corners, Uint32Array);
        const index = geometry.index;
        for (let k = 0; k < slots.length; k++) index.array.set(corners.subarray(3 * k, 3 * k + 3), 3 * slots[k]);
        const sorted = Array.from(slots).sort((a, b) => a - b);
        index.needsUpdate = true;
        if (index.updateRanges)
            for (let i = 0; i < sorted.length;) {
                let j = i;
                while (j + 1 < sorted.length && sorted[j + 1] === sorted[j] + 1) j++;
                index.addUpdateRange(3 * sorted[i], 3 * (j - i + 1));
                i = j + 1;
            }
        geometry.setDrawRange(0, 3 * delta.slots);
        this.slots = delta.slots;
        geometry.userData.vertexCount = delta.n_vertices;
        // (the skinned bounds three keeps for raycasting were of the old mesh)
        this.mesh.boundingSphere = null;
        this.mesh.boundingBox = null;
        return {rows: rows.length, faces: slots.length};
    }
}

// The rim edges a page shows, in slots like the faces: apply(delta.rims, delta.rim_slots) writes
// them and returns the live edges as a flat [a0, b0, a1, b1, ...] (a freed slot holds 0, 0).
export class RimSlots {
    constructor(edges) {
        this.ends = Uint32Array.from(edges);
    }

    apply(rims, count) {
        if (this.ends.length < 2 * count) {
            const ends = new Uint32Array(2 * count);
            ends.set(this.ends);
            this.ends = ends;
        }
        const slots = decode(rims.slots, Uint32Array), ends = decode(rims.ends, Uint32Array);
        for (let k = 0; k < slots.length; k++) this.ends.set(ends.subarray(2 * k, 2 * k + 2), 2 * slots[k]);
        const live = [];
        for (let s = 0; s < count; s++)
            if (this.ends[2 * s] !== this.ends[2 * s + 1]) live.push(this.ends[2 * s], this.ends[2 * s + 1]);
        return live;
    }
}
