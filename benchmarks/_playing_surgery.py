"""Tear strokes on a playing model: the rows of ``bench_animation`` that cut while the body moves.

Each model runs in its own process (``python -m benchmarks._playing_surgery MODEL STROKES``) after a
warm-up that compiles every kernel, and prints JSON. An incision (``bench_progressive.incision``) is
made of short strokes, each continuing the slit: a stroke's blade at t_i goes through where the last
stroke ended (that vertex skinned in the stroke's pose, as a tool that follows the skin would put it),
its blade at t_(i+1) is the next rest blade carried by the bone that dominates the skin under it. Four
ways, in one process:

* ``rest``: ``Surgery(rig)``, every stroke on the stored mesh (the incision at rest);
* ``fixed``: ``Surgery(rig, pose=P0)``, every stroke in the session's one pose (the baseline);
* ``stroke only``: ``Surgery(rig)``, stroke k in frame k of the model's first clip (``pose=``), the
  pose sampled outside the timing: what a stroke costs in a new pose; with the session's peak memory;
* ``playing``: the same, timing per frame ``rig.pose(clip, t)``, the skin of the session's whole mesh
  (what a viewer draws) and the stroke.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from .bench_progressive import _rss, incision, mesh_bytes


def model(name: str):
    """(rig, label): Arm5.glb bending its forearm (a clip made with ``clip_from_poses``: the file has
    none), or the issue's 1.52M-face capsule playing its ``wave`` clip."""
    import cgaskin
    from .bench_tear import models_dir
    if name == "arm5" and (models_dir() / "Arm5.glb").exists():
        rig = cgaskin.load(models_dir() / "Arm5.glb")
        rest = rig.rest_pose()
        keys = [rest, rest.rotate("Character1_RightForeArm", [0.3, 0.2, 1.0], 0.6),
                rest.rotate("Character1_RightArm", [0.0, 0.0, 1.0], -0.4), rest]
        return rig.with_clips(cgaskin.clip_from_poses("bend", [0.0, 0.7, 1.4, 2.0], keys)), "Arm5.glb (bend)"
    if name == "arm5":
        return cgaskin.capsule_arm(), "capsule_arm()"
    return cgaskin.capsule_arm(rings_per_segment=410, segments_around=512), "capsule_arm(410, 512)"


def _carrier(rig, blade):
    """The bone that dominates the skin where ``blade`` (2, 3) meets the rest mesh."""
    from cgaskin.surgery.bvh import TriangleBVH
    face, t = TriangleBVH(rig.vertices, rig.faces).first_hit(blade[0], blade[1])
    corners = rig.faces[face]
    hit = blade[0] + t * (blade[1] - blade[0])
    v = corners[np.argmin(np.linalg.norm(rig.vertices[corners] - hit, axis=1))]
    return int(rig.joints[v, np.argmax(rig.weights[v])])


def _carried(blade, affines, bone):
    affine = affines[bone].reshape(3, 4)
    return blade @ affine[:, :3].T + affine[:, 3]


def incision_in_poses(session, rig, blades, bones, poses, name=None, play=None):
    """Stroke k in poses[k], each from where the last one ended; seconds per stroke. ``name``: "rest"
    or "fixed" tear in the session's own pose (``pose=None``), poses[k] only carries the blades; with
    ``play`` (clip, times, draw) stroke k's pose is sampled in the timing (and the whole mesh skinned
    when ``draw``)."""
    from cgaskin.animation.skinning import skin_affine
    seconds, end = [], None
    for k in range(len(blades) - 1):
        start = time.perf_counter()
        pose = poses[k] if play is None else rig.pose(play[0], play[1][k])
        affines = pose.bone_affines()
        if play is not None and play[2]:            # what a viewer draws: the session's mesh skinned
            skin_affine(session.vertices, session.joints, session.weights, affines)
        scalpel_from = _carried(blades[k], affines, bones[k])
        scalpel_to = _carried(blades[k + 1], affines, bones[k + 1])
        if end is not None:                     # through where the slit ended, that vertex in this pose
            p = skin_affine(session.vertices[[end]], session.joints[[end]], session.weights[[end]], affines)[0]
            d = scalpel_from[1] - scalpel_from[0]
            scalpel_from = scalpel_from + p - (scalpel_from[0] + (p - scalpel_from[0]) @ d / (d @ d) * d)
        try:
            stroke = session.tear(scalpel_from, scalpel_to, pose=None if name in ("rest", "fixed") else pose)
            end = int(stroke.side_a[-1])
        except ValueError as error:
            print(f"{name} stroke {k}: {type(error).__name__}: {error}", file=sys.stderr)
            seconds.append(float("nan"))
            end = None
            continue
        seconds.append(time.perf_counter() - start)
    return seconds


def run(name: str, strokes: int) -> dict:
    import cgaskin
    for warm in ([model("arm5")[0]] if name != "arm5" else []) + [cgaskin.capsule_arm()]:   # compile first
        w = incision(warm, 3)
        b = [_carrier(warm, x) for x in w]
        p = [warm.pose(0, 0.1 * i) for i in range(3)]
        incision_in_poses(cgaskin.Surgery(warm), warm, w, b, p)
        incision_in_poses(cgaskin.Surgery(warm), warm, w, b, p, play=(0, [0.0, 0.1, 0.2], True))
        incision_in_poses(cgaskin.Surgery(warm, p[0]), warm, w, b, [p[0]] * 3, "fixed")
    rig, label = model(name)
    clip = rig.clips[0]
    times = np.linspace(0.0, clip.duration, strokes, endpoint=False)
    blades = incision(rig, strokes)
    bones = [_carrier(rig, blade) for blade in blades]
    poses = [rig.pose(clip.name, t) for t in times]
    rest = rig.rest_pose()
    out = {"label": label, "vertices": rig.n_vertices, "faces": rig.n_faces, "strokes": strokes,
           "mesh_bytes": mesh_bytes(rig)}
    out["rest"] = incision_in_poses(cgaskin.Surgery(rig), rig, blades, bones, [rest] * strokes, "rest")
    out["fixed"] = incision_in_poses(cgaskin.Surgery(rig, poses[0]), rig, blades, bones, [poses[0]] * strokes, "fixed")
    out["playing"] = incision_in_poses(cgaskin.Surgery(rig), rig, blades, bones, poses, play=(clip.name, times, True))
    Path("/proc/self/clear_refs").write_text("5")         # VmHWM := VmRSS from here on
    resident = _rss("VmRSS")
    out["stroke only"] = incision_in_poses(cgaskin.Surgery(rig), rig, blades, bones, poses)
    out["peak"] = _rss("VmHWM") - resident
    return out


if __name__ == "__main__":
    print(json.dumps(run(sys.argv[1], int(sys.argv[2]))))
