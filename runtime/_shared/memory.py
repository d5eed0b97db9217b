"""Memory: give freed memory back to the operating system, and keep working arrays for reuse.

glibc keeps freed blocks below its mmap threshold in the process heap; after a large build (a
session's BVH on a million faces frees its temporaries) the process then looks that much bigger
than what it holds, until it exits. ``malloc_trim(0)`` returns those pages. Elsewhere (macOS,
Windows, musl) there is nothing to call and this does nothing.

The other way round, a fresh array costs the operating system a page fault and a zeroed page for
each page the work writes: with 4 kB pages, more time than a million-face cut computes. numpy asks
for 2 MB pages for arrays of 4 MB and more (transparent huge pages on ``madvise`` kernels; numba's
own allocator does not): a few times cheaper, though each array's ends up to its first and from its
last 2 MB boundary still take 4 kB pages. Working arrays that an operation repeats on the same data
can be kept (``Reusable``) and cost no fault at all. Large output
arrays, which the caller keeps, come from ``recycled_empty``: their memory, once the caller drops them,
is kept for the next operation's outputs (within ``KEPT_BYTES``) instead of going back to the operating
system, so a repeated operation (a cut per sample of a dataset) finds its pages mapped.

Python's own memory has a cost of its kind: an operation written with Python containers (a drill
makes tens of thousands of lists and tuples a hole) triggers the cyclic garbage collector, whose full
collections walk every tracked object of the process (numba's own, over a hundred thousand after a
few compiled calls). ``collection_paused`` holds the collector off for such an operation: its
containers hold no cycles, reference counting frees them, and the collector runs again when it ends.

Huge pages are the wrong choice for an array written *sparsely* (scratch indexed by node or vertex,
where a stroke writes a few thousand scattered rows): each write there makes a whole 2 MB page resident,
zeroed first (``np.empty`` of 64 MB written every 512 kB is nearly all resident; numpy's ``np.zeros``
takes calloc's pages and does not ask for huge ones). ``sparse_zeros`` gives such arrays 4 kB pages,
so that a session's posed-stroke scratch holds only the pages its strokes write
(``python -m benchmarks._playing_surgery large 300`` measures a session's peak).
"""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import gc
import math
import mmap
import threading
import weakref

import numpy as np

try:
    import resource
except ImportError:                 # Windows
    resource = None

__all__ = ["release_free_memory", "minor_page_faults", "Reusable", "sparse_zeros", "recycled_empty",
           "is_recycled", "KEPT_BYTES", "collection_paused"]


def _trim():
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        return libc.malloc_trim
    except (OSError, AttributeError):
        return None


_MALLOC_TRIM = _trim()


def release_free_memory() -> None:
    """Return the heap's free pages and the recycled blocks that no array uses to the operating system
    (the heap's: glibc only)."""
    with _BLOCKS_LOCK:
        _BLOCKS[:] = [kept for kept in _BLOCKS if not kept.free()]
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


#: numpy's threshold for asking for huge pages: smaller arrays take 4 kB pages anyway
_HUGE_PAGE_THRESHOLD = 4 << 20


def sparse_zeros(shape, dtype=np.float64) -> np.ndarray:
    """A zero-filled C-contiguous writable array of ``shape`` whose memory becomes resident 4 kB at a
    time where it is written, for arrays written sparsely: anonymous memory mapped for it (zero pages,
    given back to the operating system when the array is freed), advised against transparent huge
    pages. np.zeros where the array is small or the platform has no such advice."""
    dtype = np.dtype(dtype)
    size = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if size < _HUGE_PAGE_THRESHOLD or not hasattr(mmap, "MADV_NOHUGEPAGE"):
        return np.zeros(shape, dtype)
    memory = mmap.mmap(-1, size)
    memory.madvise(mmap.MADV_NOHUGEPAGE)
    return np.frombuffer(memory, dtype).reshape(shape)


class _Block(np.ndarray):
    """The memory of recycled output arrays: a 1-D uint8 array owning its data. Being a subclass
    matters: numpy stops collapsing a view's ``base`` at a change of type, so an output array's base
    is its block, and the base of a view of the output (``frozen``) is the output."""


class _Kept:
    """A recycled block and a weak reference to the array made on it: every view of that array holds
    the array (its ``base``), so the block is free once the reference is dead."""

    __slots__ = ("block", "user")

    def __init__(self, block):
        self.block = block
        self.user = None

    def free(self) -> bool:
        return self.user is None or self.user() is None


#: every recycled block, in use or free; and the most bytes of free blocks kept
_BLOCKS: list = []
_BLOCKS_LOCK = threading.Lock()
KEPT_BYTES = 512 << 20
_ROUND = 2 << 20
#: smaller outputs take np.empty's memory (the heap's, which glibc keeps anyway)
RECYCLED_FROM = _HUGE_PAGE_THRESHOLD


def recycled_empty(shape, dtype=np.float64) -> np.ndarray:
    """``np.empty(shape, dtype)`` for an output array that the caller keeps: of 4 MB and more it is made
    on a recycled block, a free one (no array on it alive) of at least its size and at most about
    twice it when there is one, so that its pages are mapped already. A new block is a little larger
    than asked (a later call's slightly larger output fits it); free blocks beyond ``KEPT_BYTES`` go
    back to the operating system. The array's ``base`` is its block (``is_recycled``)."""
    dtype = np.dtype(dtype)
    size = math.prod(shape) * dtype.itemsize
    if size < RECYCLED_FROM:                 # (cheap: a small cut makes ten of them)
        return np.empty(shape, dtype)
    with _BLOCKS_LOCK:
        free = [kept for kept in _BLOCKS if kept.free()]
        fits = [kept for kept in free if size <= len(kept.block) <= 2 * size + _ROUND]
        if fits:
            chosen = min(fits, key=lambda kept: len(kept.block))
        else:
            chosen = _Kept(np.ndarray.__new__(_Block, (-(-(size + size // 8) // _ROUND) * _ROUND,), np.uint8))
            _BLOCKS.append(chosen)
            total = sum(len(kept.block) for kept in free)
            for old in sorted(free, key=lambda kept: len(kept.block), reverse=True):   # the largest first
                if total <= KEPT_BYTES:
                    break
                _BLOCKS.remove(old)
                total -= len(old.block)
        array = np.ndarray(shape, dtype, buffer=chosen.block)
        chosen.user = weakref.ref(array)
        return array


def is_recycled(array: np.ndarray) -> bool:
    """Whether ``array`` is an output of ``recycled_empty`` on a block (its memory is its own)."""
    return type(array.base) is _Block


def minor_page_faults() -> int:
    """Minor page faults of this process so far (``getrusage``; 0 where there is none): take the
    difference around an operation to see how many fresh pages it cost."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt if resource is not None else 0


class Reusable:
    """Working arrays that an operation takes, uses and gives back, so that the next call finds their
    pages mapped. One set is kept; calls at the same time (threads) each get a set of their own, as
    ``take`` hands a kept set to one caller only (``list.pop`` is atomic). A caller gives a set back
    only in the state ``make`` returns it in (the contract of the operation that uses it), and only
    when it no longer reads it."""

    __slots__ = ("_make", "_kept")

    def __init__(self, make):
        self._make = make
        self._kept = []

    def take(self):
        """A kept set, or a new one from ``make()``."""
        try:
            return self._kept.pop()
        except IndexError:
            return self._make()

    def give_back(self, arrays) -> None:
        """Keep ``arrays`` for the next ``take`` (unless a set is kept already)."""
        if not self._kept:
            self._kept.append(arrays)


_PAUSES = [0, False]           # operations running with the collector paused; whether it was enabled
_PAUSES_LOCK = threading.Lock()


@contextlib.contextmanager
def collection_paused():
    """Hold the cyclic garbage collector off while the block runs (module docstring); operations that
    overlap (threads) resume it when the last ends, and only if it was enabled before the first."""
    with _PAUSES_LOCK:
        if _PAUSES[0] == 0:
            _PAUSES[1] = gc.isenabled()
            gc.disable()
        _PAUSES[0] += 1
    try:
        yield
    finally:
        with _PAUSES_LOCK:
            _PAUSES[0] -= 1
            if _PAUSES[0] == 0 and _PAUSES[1]:
                gc.enable()
