// Cut rims, slits and holes: the boundary edges of the position-welded mesh (computed in Python from
// the faces: an edge that one face uses), drawn as lines that follow the skinning. Each frame the
// lines' ends are the skinned positions of their vertices (SkinnedMesh.getVertexPosition).
import * as THREE from 'three';

export class Rims {
    // meshes: the skinned meshes in file order; edges: flat [a0, b0, a1, b1, ...] vertex indices over
    // the meshes' vertices concatenated in that order (the rig's vertex order)
    constructor(scene, meshes, edges) {
        this.meshes = meshes;
        this.offsets = [];
        let offset = 0;
        for (const mesh of meshes) {
            this.offsets.push(offset);
            offset += mesh.geometry.attributes.position.count;
        }
        this.lines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({color: 0xff2bd6}));
        this.lines.frustumCulled = false;   // (its bounds change every frame)
        this.on = true;                     // (shown whenever there are some, unless turned off)
        this.setEdges(edges);
        scene.add(this.lines);
    }

    // Show these edges (flat vertex pairs) instead: cgaskin serve's page after each operation.
    setEdges(edges) {
        const vertices = this.meshes.reduce((sum, mesh) => sum + (mesh.geometry.userData.vertexCount ??
                                                                    mesh.geometry.attributes.position.count), 0);
        for (const v of edges)
            if (!(v >= 0 && v < vertices)) throw new Error(`rim vertex ${v} outside the ${vertices} vertices`);
        this.edges = Int32Array.from(edges);
        this.lines.geometry.dispose();
        this.lines.geometry = new THREE.BufferGeometry();
        this.lines.geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(this.edges.length * 3), 3));
        this.visible = this.on;
        this.update();
    }

    get count() { return this.edges.length / 2; }
    get visible() { return this.lines.visible; }
    set visible(on) { this.on = Boolean(on); this.lines.visible = this.on && this.count > 0; }

    _locate(v) {   // (mesh, local index) of a rig vertex
        let m = this.offsets.length - 1;
        while (this.offsets[m] > v) m--;
        return [this.meshes[m], v - this.offsets[m]];
    }

    // Move the lines to the skinned positions (world space); call after the skeleton's matrices are updated.
    update() {
        if (!this.lines.visible) return;
        const position = this.lines.geometry.attributes.position, p = new THREE.Vector3();
        for (let i = 0; i < this.edges.length; i++) {
            const [mesh, local] = this._locate(this.edges[i]);
            mesh.getVertexPosition(local, p).applyMatrix4(mesh.matrixWorld);
            position.setXYZ(i, p.x, p.y, p.z);
        }
        position.needsUpdate = true;
    }
}
