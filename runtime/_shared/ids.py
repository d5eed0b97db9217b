"""Sets of non-negative integer ids (rows, faces) as sorted arrays, found by marking the range the ids
span instead of by sorting them: a sort of k ids costs O(k log k) comparisons, a mark O(k + span), and
the ids an operation touches (a region's rows, a hole's faces) span little more than their count."""
from __future__ import annotations

import numpy as np


def distinct(ids) -> np.ndarray:
    """The distinct values of ``ids`` (any shape, non-negative ints), ascending (k,) int64: what
    ``np.unique(ids)`` gives."""
    flat = np.asarray(ids).ravel()
    if not len(flat):
        return np.empty(0, np.int64)
    low, high = int(flat.min()), int(flat.max())
    if high - low > 64 * len(flat):                # (ids spread far apart: a sort costs less)
        return np.unique(flat).astype(np.int64)
    marks = np.zeros(high - low + 1, bool)
    marks[flat - low] = True
    return low + np.flatnonzero(marks)
