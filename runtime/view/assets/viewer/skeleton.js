// The skeleton drawn over the mesh (three's SkeletonHelper: lines from each bone to its parent, on
// top of the surface), and the name of the bone nearest the pointer.
import * as THREE from 'three';

const HOVER_PIXELS = 14;     // how near (CSS pixels) the pointer must come to a bone's origin

export class SkeletonView {
    constructor(scene, root, bones, camera, canvas) {
        this.helper = new THREE.SkeletonHelper(root);
        this.helper.visible = false;
        scene.add(this.helper);
        this.bones = bones;
        this.camera = camera;
        this.canvas = canvas;
    }

    get visible() { return this.helper.visible; }
    set visible(on) { this.helper.visible = Boolean(on); }

    // {name: [x, y]}: each bone's origin in CSS pixels of the canvas (drawn or not)
    screenPositions() {
        const out = {}, p = new THREE.Vector3();
        const width = this.canvas.clientWidth, height = this.canvas.clientHeight;
        for (const bone of this.bones) {
            bone.getWorldPosition(p).project(this.camera);
            out[bone.name] = [(p.x + 1) / 2 * width, (1 - p.y) / 2 * height];
        }
        return out;
    }

    // The name of the bone whose origin is nearest (x, y) (canvas CSS pixels), within HOVER_PIXELS;
    // null when the skeleton is hidden or none is that near.
    boneAt(x, y) {
        if (!this.visible) return null;
        let best = null, bestDistance = HOVER_PIXELS;
        for (const [name, [bx, by]] of Object.entries(this.screenPositions())) {
            const d = Math.hypot(bx - x, by - y);
            if (d < bestDistance) { best = name; bestDistance = d; }
        }
        return best;
    }
}

// Show the hovered bone's name in `label` (a positioned div over the canvas).
export function hoverNames(skeleton, canvas, label) {
    canvas.addEventListener('pointermove', (event) => {
        const rect = canvas.getBoundingClientRect();
        const x = event.clientX - rect.left, y = event.clientY - rect.top;
        const name = skeleton.boneAt(x, y);
        label.textContent = name || '';
        label.style.display = name ? 'block' : 'none';
        label.style.left = `${x + 12}px`;
        label.style.top = `${y + 12}px`;
    });
    canvas.addEventListener('pointerleave', () => { label.style.display = 'none'; });
}
