"""The files that the client tests open: every kind the command line writes (demo, cut, tear, drill, skin)
on the built-in capsule arm, Fox.glb and Arm5.glb, a user's file with its own VEC3 ``_FOO``
attribute and that file torn, made once per session; and what cgaskin says their vertices are."""
from __future__ import annotations

import contextlib
import io
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin.app.cli import main

#: a blade that tears the Fox's flank (handle, tip) at two times: six numbers each
FOX_STROKE = ["--from", ".3", "120", ".7", ".3", "40", ".7", "--to", ".3", "120", "10.1", ".3", "40", "10.1"]
ARM_STROKE = ["--from", ".5", "30", "20", ".5", "30", "0", "--to", ".5", "42", "20", ".5", "42", "0"]
ELBOW = "Character1_RightForeArm"


def _commands(models: Path, out: Path) -> list:
    fox, arm = models / "Fox.glb", models / "Arm5.glb"
    return [
        # capsule_arm.glb, cut_upper.glb, cut_lower.glb, torn.glb (and three pictures)
        ["demo", "--out", out],
        ["cut", fox, "--normal", 0, 1, 0, "--point", 0, 40, 0, "--cap", "--clip", "Walk", "--time", .3,
         "--out", out / "fox_cut_a.glb", out / "fox_cut_b.glb"],
        ["tear", fox, *FOX_STROKE, "--opening", .5, "--out", out / "fox_torn.glb"],
        ["tear", out / "fox_foo.glb", *FOX_STROKE, "--opening", .5, "--out", out / "fox_foo_torn.glb"],
        ["skin", fox, "--clip", "Run", "--time", .5, "--out", out / "fox_run.glb"],
        ["cut", arm, "--normal", 0, 1, .2, "--point", 0, 40, 0, "--cap", "--rotate", ELBOW, 0, 0, 1, 40,
         "--out", out / "arm_cut_a.gltf", out / "arm_cut_b.glb"],
        ["tear", arm, *ARM_STROKE, "--opening", .3, "--out", out / "arm_torn.glb"],
        ["skin", arm, "--rest", "--rotate", ELBOW, 0, 0, 1, 40, "--out", out / "arm_bent.gltf"],
        # a walled hole through the walking Fox's body, an open one through the arm's forearm
        ["drill", fox, "--start", 0, 40, -50, "--end", 0, 40, 50, "--radius", 6, "--clip", "Walk", "--time", .3,
         "--out", out / "fox_drilled.glb"],
        ["drill", arm, "--start", -1, 36, -12, "--end", -1, 36, 12, "--radius", 1.5, "--no-wall",
         "--out", out / "arm_drilled.glb"],
    ]


#: static meshes written by `cgaskin skin`: the model and the pose the command line was given
SKINNED = {"fox_run.glb": ("Fox.glb", lambda rig: rig.pose("Run", .5)),
           "arm_bent.gltf": ("Arm5.glb", lambda rig: rig.rest_pose().rotate(ELBOW, [0, 0, 1], np.radians(40)))}
NAMES = ["capsule_arm.glb", "cut_upper.glb", "cut_lower.glb", "torn.glb", "fox_cut_a.glb", "fox_cut_b.glb",
         "fox_torn.glb", "fox_foo.glb", "fox_foo_torn.glb", "fox_run.glb", "arm_cut_a.gltf", "arm_cut_b.glb",
         "arm_torn.glb", "arm_bent.gltf", "fox_drilled.glb", "arm_drilled.glb"]


def load(path) -> cgaskin.Rig:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Arm5's weights are renormalised, with a warning
        return cgaskin.load(path)


def write_files(models: Path, out: Path) -> dict:
    """Run the command line (in process) to write every file of ``NAMES`` into ``out``."""
    fox = load(models / "Fox.glb")
    foo = np.c_[fox.vertices[:, 2], np.arange(fox.n_vertices), fox.vertices[:, 0] * 2]  # not widths 1 or 4
    cgaskin.save(fox.with_mesh(fox.vertices, fox.faces, fox.joints, fox.weights,
                               {**fox.attributes, "_FOO": foo}), out / "fox_foo.glb")
    for argv in _commands(models, out):
        with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main([str(a) for a in argv])
        assert code == 0, argv
    files = {name: out / name for name in NAMES}
    assert all(path.is_file() for path in files.values()), sorted(p.name for p in out.iterdir())
    return files


def clip_times(clip, keys: int = 4, between: int = 2) -> list:
    """Times to compare a clip at: ``keys`` key times spread over it (first and last included),
    ``between`` midpoints of consecutive keys, and one past the end (glTF clamps)."""
    times = np.unique(np.concatenate([np.asarray(ch.times).reshape(-1) for ch in clip.channels]))
    picks = times[np.unique(np.linspace(0, len(times) - 1, min(keys, len(times))).round().astype(int))]
    mids = [(times[i] + times[i + 1]) / 2 for i in
            np.unique(np.linspace(0, len(times) - 2, between + 2)[1:-1].round().astype(int))] if len(times) > 1 else []
    return sorted({float(t) for t in picks} | {float(t) for t in mids}) + [float(times[-1]) + .25]


@dataclass
class Expected:
    """What cgaskin says a file's vertices are: ``positions[k]`` (n, 3) in pose ``poses[k]``,
    (clip name or None for the rest pose, time); ``rig`` None for a static mesh."""
    path: Path
    rig: object
    poses: list
    positions: list

    @property
    def diagonal(self) -> float:
        p = self.positions[0]
        return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


def expected(path: Path, models: Path, times=clip_times) -> Expected:
    if path.name in SKINNED:
        model, pose = SKINNED[path.name]
        source = load(models / model)
        return Expected(path, None, [(None, 0.0)], [cgaskin.skin(source, pose(source))])
    rig = load(path)
    poses = [(None, 0.0)] + [(clip.name, t) for clip in rig.clips for t in times(clip)]
    positions = [cgaskin.skin(rig, rig.rest_pose() if clip is None else rig.pose(clip, t)) for clip, t in poses]
    return Expected(path, rig, poses, positions)
