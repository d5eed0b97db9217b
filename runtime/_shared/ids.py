"""Sets of non-negative integer ids (rows, faces) as sorted arrays, found by marking the range the ids
span instead of by sorting them: a sort of k ids costs O(k log k) comparisons, a mark O(k + span), and
the ids an operation touches (a region's rows, a hole's faces) span little more than their count. A few
ids, or ids spread far apart, are sorted (numpy's sort, then the repeats dropped: ``np.unique`` hashes,
several times slower here)."""
from __future__ import annotations

import numpy as np

#: below this many ids a sort costs less than marking their span
FEW = 512
#: ids spanning more than this many times their count are sorted, not marked
SPREAD = 64


def distinct(ids) -> np.ndarray:
    """The distinct values of ``ids`` (any shape, non-negative ints), ascending (k,) int64: what
    ``np.unique(ids)`` gives."""
    flat = np.asarray(ids, np.int64).ravel()
    if len(flat) < FEW:
        return _sorted_distinct(flat)
    low, high = int(flat.min()), int(flat.max())
    if high - low > SPREAD * len(flat):
        return _sorted_distinct(flat)
    marks = np.zeros(high - low + 1, bool)
    marks[flat - low] = True
    return low + np.flatnonzero(marks)


def ascending(ids) -> np.ndarray:
    """Distinct ids (k,) ascending: ``np.sort(ids)``, by marks when they are many."""
    return np.sort(ids) if len(ids) < FEW else distinct(ids)


def _sorted_distinct(flat) -> np.ndarray:
    ordered = np.sort(flat)
    keep = np.empty(len(ordered), bool)
    keep[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=keep[1:])
    return ordered[keep]
