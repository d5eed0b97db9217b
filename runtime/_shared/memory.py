"""Give memory that was freed back to the operating system.

glibc keeps freed blocks below its mmap threshold in the process heap; after a large build (a
session's BVH on a million faces frees its temporaries, ~130 MB) the process then looks that much
bigger than what it holds, until it exits. ``malloc_trim(0)`` returns those pages. Elsewhere (macOS,
Windows, musl) there is nothing to call and this does nothing.
"""
from __future__ import annotations

import ctypes
import ctypes.util

__all__ = ["release_free_memory"]


def _trim():
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        return libc.malloc_trim
    except (OSError, AttributeError):
        return None


_MALLOC_TRIM = _trim()


def release_free_memory() -> None:
    """Return the heap's free pages to the operating system (glibc); a no-op elsewhere."""
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)
