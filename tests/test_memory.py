"""``_shared.memory.sparse_zeros``: scratch written at scattered rows holds only the pages written."""
import sys
from pathlib import Path

import numpy as np
import pytest

from cgaskin._shared.memory import sparse_zeros


def _resident() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS in /proc/self/status")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the resident size from /proc (Linux)")
def test_a_sparse_array_holds_only_the_pages_it_writes():
    # (np.empty of this size gets huge pages where the kernel gives them on request, and these writes
    # then make nearly all of it resident: 62 MiB on the development machine)
    array = sparse_zeros((8 << 20,), np.float64)
    assert array.shape == (8 << 20,) and array.dtype == np.float64
    assert array.flags.writeable and array.flags.c_contiguous
    before = _resident()
    array[:: 1 << 16] = 1.0                                     # 128 writes, 512 KiB apart
    grown = _resident() - before
    assert grown < 2 << 20, f"128 scattered writes made {grown / 2**20:.1f} MiB resident"
    assert array.sum() == 128.0 and array[1] == 0.0


def test_small_and_multidimensional_sparse_arrays():
    small = sparse_zeros((10, 3), np.int64)
    assert small.shape == (10, 3) and small.dtype == np.int64 and not small.any()
    large = sparse_zeros((1 << 20, 3))
    large[5, 2] = 7.0
    assert large.shape == (1 << 20, 3) and large[5, 2] == 7.0 and large.reshape(-1)[17] == 7.0
