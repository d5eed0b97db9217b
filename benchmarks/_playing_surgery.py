"""Tear strokes on a playing model: the rows of ``bench_animation`` that cut while the body moves.

Each row runs in its own process (``python -m benchmarks._playing_surgery MODEL STROKES``) after a
warm-up that compiles every kernel, and prints JSON. An incision (``bench_progressive.incision``) is
made of short strokes; stroke k happens in frame k of the model's first clip: its two blades are the
rest incision's blades carried by the bone that dominates the skin under them, in that frame's pose.
Three ways, all in one process on the same strokes:

* ``fixed``: ``Surgery(rig, pose=P0)``: every stroke in the session's one pose (the baseline);
* ``playing``: ``Surgery(rig)`` and, per frame, ``rig.pose(clip, t)``, ``cgaskin.skin`` of the whole
  mesh (what a viewer draws) and ``session.tear(..., pose=)`` in that pose;
* ``stroke only``: the same strokes in new poses, the pose sampled and the mesh skinned outside the
  timing (what the stroke itself costs in a new pose), with the session's peak memory.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from .bench_progressive import _rss, incision, mesh_bytes


def model(name: str):
    """(rig, label): Arm5.glb, or the issue's 1.52M-face capsule playing its ``wave`` clip."""
    import cgaskin
    from .bench_tear import models_dir
    if name == "arm5":
        path = models_dir() / "Arm5.glb"
        if path.exists() and cgaskin.load(path).clips:
            return cgaskin.load(path), "Arm5.glb"
        return cgaskin.capsule_arm(), "capsule_arm()"
    return cgaskin.capsule_arm(rings_per_segment=410, segments_around=512), "capsule_arm(410, 512)"


def posed_blades(rig, blades, poses):
    """(k, 2, 3) blades: blade k carried into poses[k] by the bone with the largest weight on the rest
    vertex nearest to its tip (the skin under the blade moves with that bone)."""
    from cgaskin.surgery.bvh import TriangleBVH
    bvh = TriangleBVH(rig.vertices, rig.faces)
    out = np.empty_like(blades)
    for k, (blade, pose) in enumerate(zip(blades, poses)):
        face, t = bvh.first_hit(blade[0], blade[1])
        hit = blade[0] + t * (blade[1] - blade[0])
        corners = rig.faces[face]
        v = corners[np.argmin(np.linalg.norm(rig.vertices[corners] - hit, axis=1))]
        bone = rig.joints[v, np.argmax(rig.weights[v])]
        affine = pose.bone_affines()[bone].reshape(3, 4)
        out[k] = blade @ affine[:, :3].T + affine[:, 3]
    return out


def run(name: str, strokes: int) -> dict:
    import cgaskin
    warm, _ = model("arm5") if name != "arm5" else (None, None)
    rig, label = model(name)
    for r in ([warm] if warm is not None else []) + [rig]:        # compile everything first
        w = incision(r, 3)
        s = cgaskin.Surgery(r)
        clip = r.clips[0]
        for i in range(2):
            p = r.pose(clip.name, 0.1 * i)
            s.tear(*posed_blades(r, w[i:i + 2], [p, p]), pose=p)
        cgaskin.Surgery(r, r.pose(clip.name, 0.0)).tear(*posed_blades(r, w[:2], [p, p]))
    clip = rig.clips[0]
    times = np.linspace(0.0, clip.duration, strokes, endpoint=False)
    blades = incision(rig, strokes)
    poses = [rig.pose(clip.name, t) for t in times]
    pairs = [posed_blades(rig, blades[k:k + 2], [poses[k], poses[k]]) for k in range(strokes)]
    fixed_pairs = [posed_blades(rig, blades[k:k + 2], [poses[0], poses[0]]) for k in range(strokes)]
    out = {"label": label, "vertices": rig.n_vertices, "faces": rig.n_faces, "strokes": strokes,
           "mesh_bytes": mesh_bytes(rig)}

    session = cgaskin.Surgery(rig, poses[0])
    out["fixed"] = _timed(lambda k: session.tear(*fixed_pairs[k]), strokes)

    session = cgaskin.Surgery(rig)

    def playing(k):
        pose = rig.pose(clip.name, times[k])
        cgaskin.skin(rig, pose)
        session.tear(*pairs[k], pose=pose)
    out["playing"] = _timed(playing, strokes)

    Path("/proc/self/clear_refs").write_text("5")         # VmHWM := VmRSS from here on
    resident = _rss("VmRSS")
    session = cgaskin.Surgery(rig)
    out["stroke only"] = _timed(lambda k: session.tear(*pairs[k], pose=poses[k]), strokes)
    out["peak"] = _rss("VmHWM") - resident
    return out


def _timed(stroke, count: int) -> list:
    """Seconds of ``stroke(k)`` for k = 0 .. count - 1 (a stroke that raises counts as NaN)."""
    seconds = []
    for k in range(count):
        start = time.perf_counter()
        try:
            stroke(k)
        except ValueError as error:
            print(f"stroke {k}: {type(error).__name__}: {error}", file=sys.stderr)
            seconds.append(float("nan"))
            continue
        seconds.append(time.perf_counter() - start)
    return seconds


if __name__ == "__main__":
    print(json.dumps(run(sys.argv[1], int(sys.argv[2]))))
