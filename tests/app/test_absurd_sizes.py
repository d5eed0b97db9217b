"""Absurd sizes are refused up front with one line, not after minutes with a MemoryError traceback
(issue 43 D12, D16): ``skin --frames``, ``tear --strokes``, a batch spec's ``count``, and the library
calls that allocate in proportion to a size the caller gave (``rig.poses``, ``skin`` of many frames,
``capsule_arm``).

Each call runs under an address-space limit a few GiB above what the process uses (``ulimit -v``), so
that a regression fails fast with a MemoryError here instead of taking the machine's memory; the
refusals allocate nothing of the size asked for.
"""
import contextlib
import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cgaskin
from cgaskin.animation.poses import Poses
from cgaskin.app.cli import main
from cgaskin.errors import InvalidInputError, MemoryLimitError
from tests.app import test_edges_met as edges_met

#: room left above the process's size while a call runs
HEADROOM = 3 << 30
ABSURD = 100_000_000


def _virtual_size() -> int:
    return int(Path("/proc/self/statm").read_text().split()[0]) * os.sysconf("SC_PAGE_SIZE")


@contextlib.contextmanager
def limited_address_space(headroom: int = HEADROOM):
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    resource.setrlimit(resource.RLIMIT_AS, (_virtual_size() + headroom, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@pytest.fixture(scope="module")
def arm_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("arm") / "arm.glb"
    cgaskin.save(cgaskin.capsule_arm(), path)
    return path


def one_line_error(capsys, argv, folder) -> str:
    """``test_edges_met.one_line_error`` (exit 2, one line, nothing written) under the address-space limit."""
    with limited_address_space():
        return edges_met.one_line_error(capsys, argv, folder)


def test_skin_refuses_frames_beyond_the_memory(arm_file, tmp_path, capsys):
    line = one_line_error(capsys, ["skin", arm_file, "--clip", "wave", "--frames", ABSURD, "--out",
                                   tmp_path / "o.glb"], tmp_path)
    assert f"--frames {ABSURD}" in line and "memory" in line and "available" in line


def test_max_memory_is_a_limit_the_user_gives(arm_file, tmp_path, capsys):
    # 2000 frames of the arm fit in this machine's memory, not in 1 MiB
    line = one_line_error(capsys, ["skin", arm_file, "--clip", "wave", "--frames", 2000, "--max-memory", "1M",
                                   "--out", tmp_path / "o.glb"], tmp_path)
    assert "--frames 2000" in line and "limit of 1.0 MiB" in line
    assert main(["skin", str(arm_file), "--clip", "wave", "--frames", "2", "--max-memory", "1G",
                 "--out", str(tmp_path / "o.glb")]) == 0
    assert (tmp_path / "o_0001.glb").is_file()


@pytest.mark.parametrize("value", ["lots", "-1", "0", "1.5Q", "nan"])
def test_max_memory_must_be_a_size(arm_file, tmp_path, capsys, value):
    line = one_line_error(capsys, ["skin", arm_file, "--max-memory", value, "--out", tmp_path / "o.glb"], tmp_path)
    assert f"--max-memory {value}" in line


def test_tear_refuses_a_strokes_file_without_end(arm_file, tmp_path, capsys):
    line = one_line_error(capsys, ["tear", arm_file, "--strokes", "/dev/zero", "--out", tmp_path / "t.glb"], tmp_path)
    assert "--strokes /dev/zero" in line and "line 1" in line


def test_tear_refuses_more_strokes_than_the_memory_limit(arm_file, tmp_path, capsys):
    strokes = tmp_path / "strokes.txt"
    strokes.write_text("0.6 0.05 1 0.6 0.05 0\n1.2 0.05 1 1.2 0.05 0\n" * 20_000)
    line = one_line_error(capsys, ["tear", arm_file, "--strokes", strokes, "--max-memory", "1M",
                                   "--out", tmp_path / "t.glb"], tmp_path)
    assert f"--strokes {strokes}" in line and "limit of 1.0 MiB" in line


def test_batch_refuses_a_count_beyond_the_memory(tmp_path, arm_file):
    """A subprocess, as a user runs it: before, it expanded items silently for minutes."""
    spec = tmp_path / "spec.toml"
    spec.write_text(f'[[models]]\npath = "{arm_file}"\n[[operations]]\nkind = "cut"\ncount = {ABSURD}\n')

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (4 << 30, resource.getrlimit(resource.RLIMIT_AS)[1]))

    done = subprocess.run([sys.executable, "-m", "cgaskin", "batch", str(spec), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120, preexec_fn=limit)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr[-2000:]
    assert lines[0].startswith("cgaskin batch: error: ") and f"{ABSURD}" in lines[0] and "memory" in lines[0]
    assert not (tmp_path / "out" / "manifest.parquet").exists()


def test_the_library_refuses_too_many_times_and_frames():
    arm = cgaskin.capsule_arm()
    many = np.broadcast_to(0.5, (10**12,))            # (a view: no memory of its own)
    with limited_address_space(), pytest.raises(MemoryLimitError, match="times"):
        arm.poses("wave", many)
    one = arm.poses("wave", [0.5])
    frames = Poses(arm.skeleton, *(np.broadcast_to(a, (10**10,) + a.shape[1:]) for a in
                                   (one.times, one.versors, one.matrices, one.similar)))
    with limited_address_space(), pytest.raises(MemoryLimitError, match="frames"):
        cgaskin.skin(arm, frames)
    with limited_address_space(), pytest.raises(MemoryLimitError, match="segments_around"):
        cgaskin.capsule_arm(rings_per_segment=10**6, segments_around=10**6)
    assert issubclass(MemoryLimitError, MemoryError) and issubclass(MemoryLimitError, InvalidInputError)
