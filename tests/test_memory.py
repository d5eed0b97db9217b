"""``_shared.memory``: scratch written at scattered rows (``sparse_zeros``) holds only the pages written;
recycled output arrays (``recycled_empty``) reuse only memory that no array uses any more; the garbage
collector held off during an operation (``collection_paused``) runs again when the last one ends."""
import sys
from pathlib import Path

import numpy as np
import pytest

from cgaskin._shared import memory
from cgaskin._shared.frozen import frozen, kernel_array
from cgaskin._shared.memory import (collection_paused, is_recycled, recycled_empty, release_free_memory,
                                     sparse_zeros)


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


# --- recycled output arrays ---------------------------------------------------------------------

def _address(array) -> int:
    return array.__array_interface__["data"][0]


@pytest.fixture
def recycle_small(monkeypatch):
    """Recycled blocks for arrays of any size (the tests' arrays are small), and none left over."""
    monkeypatch.setattr(memory, "RECYCLED_FROM", 1)
    release_free_memory()
    yield
    release_free_memory()


def test_a_dropped_output_gives_its_memory_to_the_next(recycle_small):
    first = recycled_empty((1000, 3))
    address = _address(first)
    del first
    second = recycled_empty((1000, 4), np.int64)          # a little larger: the block has room
    assert _address(second) == address
    assert second.shape == (1000, 4) and second.dtype == np.int64 and second.flags.writeable
    assert is_recycled(second)


def test_memory_is_not_reused_while_any_view_of_its_array_lives(recycle_small):
    first = recycled_empty((1000, 3))
    first[:] = 7.0
    views = [first[::2], first.reshape(-1), frozen(first), memoryview(first)]
    del first
    for _ in range(3):
        other = recycled_empty((1000, 3))
        other[:] = -1.0
        assert not any(np.shares_memory(other, np.asarray(v)) for v in views)
        del other
    assert all((np.asarray(v) == 7.0).all() for v in views)


def test_a_frozen_recycled_array_is_not_copied_and_its_kernel_array_is_it(recycle_small):
    array = recycled_empty((100, 3))
    view = frozen(array)
    assert np.shares_memory(view, array) and not view.flags.writeable
    assert kernel_array(view) is array
    assert not frozen(array[1:]).base is array      # a view of it is still copied


def test_free_blocks_beyond_the_kept_bytes_go_back(recycle_small, monkeypatch):
    monkeypatch.setattr(memory, "KEPT_BYTES", 3 * memory._ROUND)
    arrays = [recycled_empty((k * 10_000,)) for k in range(1, 30)]      # 29 blocks, up to 4.6 MB
    assert len(memory._BLOCKS) == 29
    del arrays
    _ = recycled_empty((10_000_000,))                                   # fits none: a new block
    free = [kept for kept in memory._BLOCKS if kept.free()]
    assert sum(len(kept.block) for kept in free) <= 3 * memory._ROUND
    release_free_memory()
    assert len(memory._BLOCKS) == 1                                     # the one in use


def test_outputs_made_in_threads_never_share_memory(recycle_small):
    from concurrent.futures import ThreadPoolExecutor

    def make(i):
        array = recycled_empty((500 + i % 7, 3))
        array[:] = i
        return array

    with ThreadPoolExecutor(4) as pool:
        for round_ in range(5):
            arrays = list(pool.map(make, range(40)))
            assert all((a == i).all() for i, a in enumerate(arrays))
            del arrays


# --- the collector held off during an operation -----------------------------------------------------

def test_collection_is_paused_inside_and_resumed_after():
    import gc
    assert gc.isenabled()
    with collection_paused():
        assert not gc.isenabled()
        with collection_paused():                   # nested (a session's drill runs the functional one)
            assert not gc.isenabled()
        assert not gc.isenabled()
    assert gc.isenabled()
    with pytest.raises(ZeroDivisionError):          # an operation that raises resumes it too
        with collection_paused():
            1 / 0
    assert gc.isenabled()


def test_a_collector_the_caller_disabled_stays_disabled():
    import gc
    gc.disable()
    try:
        with collection_paused():
            pass
        assert not gc.isenabled()
    finally:
        gc.enable()


def test_overlapping_operations_in_threads_resume_the_collector_once_all_end():
    import gc
    import threading
    entered, leave = threading.Barrier(3), threading.Event()

    def operation():
        with collection_paused():
            entered.wait()
            leave.wait()

    threads = [threading.Thread(target=operation) for _ in range(2)]
    for t in threads:
        t.start()
    entered.wait()
    assert not gc.isenabled()
    leave.set()
    for t in threads:
        t.join()
    assert gc.isenabled()
