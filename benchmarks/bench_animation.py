"""Frames from clips: sampling a clip into a pose against skinning it, per frame and in batches, in one
process.

    python -m benchmarks.bench_animation [--frames 1000] [--repeat 21] [--joints 551] [--strokes 60]
        [--large-strokes 300]

Models: Fox (its "Walk" clip), the largest other shared glTF rig by node count, and a capsule arm with
as many joints as ACL's rig playing its ``wave`` clip (``--joints``, 551: where one call's fixed cost
no longer hides the rate per joint); a rig without clips gets a synthetic one (``clip_from_poses``: 30
keys, every node turned, so every node has translation, rotation and scale channels).
Rows (µs per frame, medians of rounds that time each row beside ``skin`` alone):

* ``skin`` alone (the pose made once): the baseline of the "x skin" column;
* ``rig.pose(clip, t)`` per frame, t stepping through a 60 fps playback of the clip (as a viewer
  asks; the sampler's cursor finds the key interval without a search while t stays in it or enters
  the next), with joints (skeleton nodes) sampled per second and that rate over ACL's 1.9e7 bones/s
  (design.md section 10);
* ``rig.pose`` + ``skin`` per frame (the goal: at most 2x ``skin`` alone);
* ``rig.poses`` + ``skin(rig, poses)`` over ``--frames`` frames, per frame (and the sampling alone).

Each group of rows is a function of a ``Case`` returning rows; add a group to ``ROW_GROUPS``.

A second table, surgery on a playing model (``_playing_surgery.py``, each model in its own process):
an incision of short strokes on Arm5 bending its forearm and on the issue's 1.52M-face capsule playing
``wave``, each stroke from where the last one ended: in a ``Surgery`` at rest, in its one pose, in a new
pose per stroke (the stroke alone, and per frame the pose, the skin of the whole mesh and the stroke),
with ratios to the fixed pose and the peak memory of the new-pose session over the mesh's own arrays
(its mesh copy included; left blank under 16 MiB, where the process's resident size is too coarse).
The capsule's 300 strokes each cut about 1/400 of its length: a scalpel dragged at frame rate.
"""
from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np

import cgaskin

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table

MODELS = Path(os.environ.get("CGASKIN_MODELS", Path(__file__).resolve().parents[2] / "shared" / "models"))
ACL_BONES_PER_SECOND = 1.9e7       # ACL 2.1, 551 bones decoded in 28.8 µs (design.md section 10)


class Case:
    """A rig and the clip played on it, the times of a playback, and its ``skin`` alone (the baseline
    that every group times beside its own rows)."""

    def __init__(self, label: str, rig, clip: str, frames: int, repeat: int):
        self.label, self.rig, self.clip, self.repeat = label, rig, clip, repeat
        duration = rig.clips[rig.clip_index(clip)].duration
        self.times = np.linspace(0.0, duration, frames)
        self.time = 0.37 * duration
        self.out = np.empty_like(rig.vertices)
        pose = rig.pose(clip, self.time)
        self.skin_alone = lambda: cgaskin.skin(rig, pose, out=self.out)
        self.skin_us = None

    @property
    def joints(self) -> int:
        return self.rig.skeleton.n_nodes

    def time_us(self, calls: dict) -> dict:
        """{name: median µs per frame} of ``calls`` ({name: (fn, frames it makes)}) and of the baseline
        ``skin`` alone (``self.skin_us``), timed in interleaved rounds: a burst of load on this shared
        machine slows every candidate of a round alike, so ratios hold where absolute times drift."""
        calls = {"skin": (self.skin_alone, 1), **calls}
        samples = {name: [] for name in calls}
        for _ in range(self.repeat):
            for name, (fn, frames) in calls.items():
                samples[name].append(median_seconds(fn, 1, warmup=0, min_time=0.01) * 1e6 / frames)
        out = {name: float(np.median(values)) for name, values in samples.items()}
        self.skin_us = out.pop("skin")
        return out

    def row(self, what: str, us: float, sampled: bool = False) -> list:
        """[model, what, µs per frame, joints/s, x ACL, x skin]; the rates only for rows that sample;
        x skin against the baseline of the last ``time_us``."""
        rate = self.joints / us * 1e6 if sampled else None
        return [self.label, what, us, rate or "", rate / ACL_BONES_PER_SECOND if rate else "", us / self.skin_us]


def frame_rows(case: Case) -> list:
    """One frame at a time: skin alone, the pose alone, the pose and its skin."""
    rig, clip, out = case.rig, case.clip, case.out
    duration = rig.clips[rig.clip_index(clip)].duration
    playback = itertools.cycle([float(t) for t in np.arange(0.0, duration, 1 / 60)] or [0.0])
    us = case.time_us({"pose": (lambda: rig.pose(clip, next(playback)), 1),
                       "pose + skin": (lambda: cgaskin.skin(rig, rig.pose(clip, next(playback)), out=out), 1)})
    return [case.row("skin alone (pose made once)", case.skin_us),
            case.row("rig.pose per frame", us["pose"], sampled=True),
            case.row("rig.pose + skin per frame", us["pose + skin"])]


def batch_rows(case: Case) -> list:
    """Many frames in one call each: the poses, then the poses and their skins."""
    rig, clip, times = case.rig, case.clip, case.times
    n = len(times)
    out = np.empty((n,) + rig.vertices.shape)
    us = case.time_us({"poses": (lambda: rig.poses(clip, times), n),
                       "poses + skin": (lambda: cgaskin.skin(rig, rig.poses(clip, times), out=out), n)})
    return [case.row(f"rig.poses, {n} frames, per frame", us["poses"], sampled=True),
            case.row(f"rig.poses + skin(rig, poses), {n} frames, per frame", us["poses + skin"])]


# Row groups, each a function of a Case returning rows (``case.time_us`` times its calls beside skin
# alone, ``case.row`` makes the columns)
ROW_GROUPS = [frame_rows, batch_rows]


def stroke_rows(name: str, strokes: int) -> list:
    """Surgery on a playing model: ``_playing_surgery`` run in a process of its own."""
    out = subprocess.run([sys.executable, "-m", "benchmarks._playing_surgery", name, str(strokes)],
                         capture_output=True, text=True, cwd=Path(__file__).resolve().parent.parent)
    if out.returncode:
        print(out.stderr, file=sys.stderr)
        raise SystemExit(f"bench_animation: the {name} strokes failed")
    r = json.loads(out.stdout.strip().splitlines()[-1])
    ms = {way: np.array(r[way]) * 1e3 for way in ("rest", "fixed", "stroke only", "playing")}
    fixed = float(np.nanmedian(ms["fixed"]))
    rows = []
    for way, what in (("rest", "Surgery(rig).tear, at rest"), ("fixed", "Surgery(rig, pose).tear, its one pose"),
                      ("stroke only", "tear(..., pose=) in a new pose per stroke"),
                      ("playing", "per frame: pose + skin (whole mesh) + stroke")):
        median = float(np.nanmedian(ms[way]))
        # (below a few MiB a process's resident size moves by more than the session's arrays)
        peak = f"{r['peak'] / r['mesh_bytes']:.2f}" if way == "stroke only" and r["mesh_bytes"] > 2**24 else ""
        rows.append([r["label"], r["faces"], what, int(np.isfinite(ms[way]).sum()), median,
                     float(ms[way][0]), median / fixed, peak])
    return rows


def _load(path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return cgaskin.load(path)


def _with_clip(rig):
    """The rig and a clip name: its first clip, else a synthetic one on every node."""
    if rig.clips:
        return rig, rig.clips[0].name
    rng = np.random.default_rng(0)
    rest = rig.rest_pose()
    keys = []
    for _ in range(30):
        pose = rest
        for node in range(rig.skeleton.n_nodes):
            pose = pose.rotate(node, rng.normal(size=3), rng.uniform(-0.3, 0.3))
        keys.append(pose)
    return rig.with_clips(cgaskin.clip_from_poses("synthetic", np.linspace(0.0, 2.0, 30), keys)), "synthetic"


def cases(frames: int, repeat: int, joints: int) -> list:
    """Fox with its Walk clip, the largest other shared glTF rig by node count (then vertices), and a
    capsule arm of ``joints`` joints (0: none) playing its first clip."""
    fox = _load(MODELS / "Fox.glb")
    others = [(path.name, _load(path)) for path in sorted(MODELS.glob("*.gl*")) if path.name != "Fox.glb"]
    name, largest = max(others, key=lambda item: (item[1].skeleton.n_nodes, item[1].n_vertices))
    largest, clip = _with_clip(largest)
    return [Case("Fox.glb", fox, "Walk", frames, repeat),
            Case(f"{name} ({clip!r})", largest, clip, frames, repeat)] + (
        [Case(f"capsule_arm({joints}) ({clip!r})", arm, clip, frames, repeat)
         for arm, clip in [_with_clip(cgaskin.capsule_arm(n_joints=joints, rings_per_segment=2))]]
        if joints > 0 else [])


@writes_tables
def main(argv=None):
    ap = benchmark_parser(__doc__)
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--joints", type=int, default=551, help="joints of the synthetic capsule arm (0: none)")
    ap.add_argument("--strokes", type=int, default=60, help="strokes on Arm5 (0: no stroke rows)")
    ap.add_argument("--large-strokes", type=int, default=300, help="strokes on the 1.52M-face capsule (0: none)")
    args = ap.parse_args(argv)
    rows = []
    for case in cases(args.frames, args.repeat, args.joints):
        rig = case.rig
        channels = len(rig.clips[rig.clip_index(case.clip)].channels)
        print(f"{case.label}: {case.joints} nodes, {rig.skeleton.n_bones} bones, {rig.n_vertices} vertices, "
              f"{channels} channels")
        for group in ROW_GROUPS:
            rows += group(case)
    print_table(f"Frames from clips (median µs per frame of {args.repeat} interleaved rounds; x skin: over skin "
                f"alone of the same model in the same rounds)",
                ["model", "what", "µs/frame", "joints/s", "x ACL", "x skin"],
                rows)
    strokes = [row for name, count in (("arm5", args.strokes), ("large", args.large_strokes)) if count > 0
               for row in stroke_rows(name, count)]
    if strokes:
        print_table("Surgery on a playing model: an incision, each stroke from where the last one ended (median ms "
                    "per stroke; first: the first stroke, which makes the bone influences of the session's tree; "
                    "x fixed: over the session in its one pose; peak: the new-pose session's peak memory "
                    "over the mesh's arrays)", ["model", "faces", "what", "strokes", "median ms", "first ms",
                                                "x fixed", "peak / mesh"], strokes)


if __name__ == "__main__":
    main()
