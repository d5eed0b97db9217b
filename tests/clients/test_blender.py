"""Blender 5.0 opens every file cgaskin writes, whatever Python's string hashing: its glTF importer
concatenates application attributes ("_NAME") in a set's order, so a file that mixes widths fails
for some PYTHONHASHSEED values (see rigs/export.py). One bpy process per seed imports all files;
the mesh as imported must be cgaskin's (vertex order, positions, "_NAME" attribute values) and the
first clip, evaluated at a middle key time (Blender interpolates rotations by nlerp and normalises
weights: keys are where it agrees exactly), must be ``cgaskin.skin``'s pose to 1e-5 of the diagonal.
A file in the layout of earlier versions (weight residuals as VEC4 attributes beside a SCALAR
_TEAR) shows the failure this guards against."""
import json
import os
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pygltflib
import pytest

import cgaskin

from .conftest import SUMMARY
from .files import NAMES, SKINNED, expected, load

SEEDS = (0, 1, 2, 3, 4, 5)
TOLERANCE = 1e-5  # of the bounding box diagonal
SCRIPT = Path(__file__).resolve().parent / "blender_positions.py"
LEGACY = "fox_torn_legacy.glb"


def legacy_layout(path: Path, out: Path) -> Path:
    """``path`` rewritten as earlier versions wrote it: weight residuals as _CGASKIN_ attributes."""
    doc = pygltflib.GLTF2().load(str(path))
    (prim,) = doc.meshes[0].primitives
    ours = prim.extras["cgaskin"]
    assert {"WEIGHTS_0_LO", "WEIGHTS_0_LO2"} <= set(ours) and "ATTRIBUTE_WIDTHS" not in ours
    for name in ("LO", "LO2"):
        setattr(prim.attributes, f"_CGASKIN_WEIGHTS_0_{name}", ours.pop(f"WEIGHTS_0_{name}"))
    doc.save(str(out))
    return out


def first_key_in_the_middle(clip) -> float:
    times = np.unique(np.concatenate([np.asarray(ch.times).reshape(-1) for ch in clip.channels]))
    return float(times[len(times) // 2])


@pytest.fixture(scope="module")
def blender_runs(blender, client_files, models_dir, tmp_path_factory):
    """(files, {seed: npz of blender_positions.py}, {name: Expected}) for every seed."""
    start = time.perf_counter()
    work = tmp_path_factory.mktemp("blender")
    files = {**client_files, LEGACY: legacy_layout(client_files["fox_torn.glb"], work / LEGACY)}
    wanted = {}
    for name in NAMES:
        rig = None if name in SKINNED else load(client_files[name])
        pose = [rig.clips[0].name, first_key_in_the_middle(rig.clips[0])] if rig is not None and rig.clips else None
        wanted[name] = expected(client_files[name], models_dir,
                                times=lambda clip, pose=pose: [pose[1]] if pose and clip.name == pose[0] else [])
    jobs = [{"path": str(path), "pose": None} for path in files.values()]
    for job, name in zip(jobs, files):
        if name in wanted and len(wanted[name].poses) > 1:
            job["pose"] = list(wanted[name].poses[1])
    (work / "jobs.json").write_text(json.dumps(jobs))

    def import_all(seed):
        return subprocess.run([blender, str(SCRIPT), str(work / "jobs.json"), str(work / f"{seed}.npz")],
                              capture_output=True, text=True, timeout=300,
                              env={**os.environ, "PYTHONHASHSEED": str(seed)})

    runs = {}
    with ThreadPoolExecutor(max_workers=2) as pool:  # two processes at a time: a 2-core machine
        for seed, run in zip(SEEDS, pool.map(import_all, SEEDS)):
            assert run.returncode == 0, f"bpy process (PYTHONHASHSEED={seed}) failed:\n{run.stderr[-4000:]}"
            with np.load(work / f"{seed}.npz") as npz:
                runs[seed] = {key: npz[key] for key in npz.files}
    n_vertices = sum(len(e.positions[0]) for e in wanted.values())
    SUMMARY.append(f"Blender: {len(NAMES)} files ({n_vertices} vertices, "
                   f"{sum(len(e.poses) > 1 for e in wanted.values())} posed at a key time) imported under "
                   f"PYTHONHASHSEED {', '.join(map(str, SEEDS))} in {time.perf_counter() - start:.1f} s "
                   f"({len(SEEDS)} bpy processes, two at a time)")
    return files, runs, wanted


@pytest.mark.parametrize("name", NAMES)
def test_blender_imports_the_file_as_cgaskin_reads_it(blender_runs, name):
    files, runs, wanted = blender_runs
    e = wanted[name]
    i = list(files).index(name)
    stored = e.rig.vertices if e.rig is not None else e.positions[0]
    # Blender keeps the vertices that faces use, in file order
    used = np.unique(e.rig.faces) if e.rig is not None else slice(None)
    for seed, run in runs.items():
        where = f"{name}, PYTHONHASHSEED={seed}"
        assert f"{i}/error" not in run, f"{where}: Blender's importer failed: {run.get(f'{i}/error')}"
        assert run[f"{i}/stored"].shape == stored[used].shape, where
        assert np.abs(run[f"{i}/stored"] - stored[used]).max() <= TOLERANCE * e.diagonal, where
        attributes = {} if e.rig is None else {k: v for k, v in e.rig.attributes.items() if k.startswith("_")}
        assert sorted(k.split("/", 1)[1] for k in run if k.startswith(f"{i}/_")) == sorted(attributes), where
        for attribute, values in attributes.items():
            theirs = run[f"{i}/{attribute}"]
            assert np.array_equal(theirs[:, :values.shape[1]], values[used].astype(np.float32)), (where, attribute)
            assert (theirs[:, values.shape[1]:] == 0).all(), (where, attribute)  # the padding
        if len(e.poses) > 1:
            error = np.abs(run[f"{i}/posed"] - e.positions[1][used]).max() / e.diagonal
            assert error <= TOLERANCE, f"{where}: posed {e.poses[1]} differs by {error:.2e} of the diagonal"


def test_the_layout_of_earlier_versions_broke_blender(blender_runs):
    """The regression: residual VEC4 attributes beside a SCALAR _TEAR fail for some hash seeds (the
    failure this layout removes); cgaskin itself still reads such files exactly."""
    files, runs, _ = blender_runs
    i = list(files).index(LEGACY)
    failed = [seed for seed, run in runs.items() if f"{i}/error" in run]
    assert failed, "Blender imported the old layout under every seed: is the importer fixed?"
    assert "concatenation axis must match exactly" in str(runs[failed[0]][f"{i}/error"])
    old, new = cgaskin.load(files[LEGACY]), cgaskin.load(files["fox_torn.glb"])
    assert np.array_equal(old.weights, new.weights) and np.array_equal(old.vertices, new.vertices)
    SUMMARY.append(f"Blender on the layout of earlier versions: failed under PYTHONHASHSEED "
                   f"{', '.join(map(str, failed))} of {', '.join(map(str, SEEDS))}")
