// Clips: one AnimationMixer over the loaded scene, one action at a time.
//
// The mixer writes a node only when a channel's value changed since it last wrote it, so nothing
// else may write the nodes' position/quaternion/scale while a clip plays: dilations are applied when
// the node's matrix is composed (dilate()), and a switch of clip puts every node back at its rest
// transform (what glTF gives a node the clip does not animate, as cgaskin's rig.pose does) and drops
// the mixer's cached bindings.
import * as THREE from 'three';

export class Playback {
    constructor(root, clips) {
        this.root = root;
        this.clips = clips;
        this.mixer = new THREE.AnimationMixer(root);
        this.action = null;
        this.playing = false;
        this.speed = 1;
        this.loop = true;
        this.rest = [];   // [object, position, quaternion, scale] of every node under root
        root.traverse((object) => this.rest.push(
            [object, object.position.clone(), object.quaternion.clone(), object.scale.clone()]));
    }

    get clip() { return this.action ? this.action.getClip() : null; }
    get duration() { return this.clip ? this.clip.duration : 0; }
    get time() { return this.action ? this.action.time : 0; }

    setClip(name) {
        const clip = this.clips.find((c) => c.name === name);
        if (!clip) throw new Error(`no clip ${JSON.stringify(name)}; the clips: ` +
                                   (this.clips.map((c) => c.name).join(', ') || 'none'));
        if (this.action) this.action.stop();
        this.mixer.uncacheRoot(this.root);
        for (const [object, position, quaternion, scale] of this.rest) {
            object.position.copy(position);
            object.quaternion.copy(quaternion);
            object.scale.copy(scale);
        }
        this.action = this.mixer.clipAction(clip);
        this._applyLoop();
        this.action.reset().play();
        this.setTime(0);
    }

    setLoop(loop) {
        this.loop = Boolean(loop);
        this._applyLoop();
    }

    _applyLoop() {
        if (!this.action) return;
        if (this.loop) this.action.setLoop(THREE.LoopRepeat, Infinity);
        else this.action.setLoop(THREE.LoopOnce, 1);
        this.action.clampWhenFinished = true;   // (glTF holds the last key after the end)
    }

    // Put the clip at `time` seconds (clamped to the clip when not looping, wrapped when looping).
    setTime(time) {
        if (!this.action) return 0;
        this.action.enabled = true;
        this.action.paused = false;           // (a LoopOnce action pauses itself at its end)
        this.mixer.setTime(Math.max(0, time));
        return this.action.time;
    }

    // Advance by `seconds` of wall time (scaled by the speed) when playing; apply the pose.
    advance(seconds) {
        this.mixer.update(this.playing ? seconds * this.speed : 0);
        if (this.playing && !this.loop && this.action && this.action.time >= this.duration) this.playing = false;
    }
}

// Let `node` be dilated: its local matrix becomes T·R·S·D with D the uniform scale
// node.userData.dilation (1 when unset), the joint's versor times the algebra's dilator about the
// joint (what cgaskin's Pose.dilate does), without touching node.scale, which belongs to the mixer.
export function dilatable(node) {
    const scale = new THREE.Vector3();
    node.updateMatrix = function updateMatrix() {
        scale.copy(this.scale).multiplyScalar(this.userData.dilation ?? 1);
        this.matrix.compose(this.position, this.quaternion, scale);
        this.matrixWorldNeedsUpdate = true;
    };
}
