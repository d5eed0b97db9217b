"""Arrays that grow at their end without a copy per step: spare capacity, doubled when full."""
from __future__ import annotations

import numpy as np


class Rows:
    """The first ``n`` rows of a (capacity, ...) array; ``append`` writes after them, doubling the
    capacity when full (amortised O(rows appended)); ``view`` is ``data[:n]`` (no copy)."""

    def __init__(self, values, spare: float = 0.25):
        values = np.asarray(values)
        capacity = max(16, int(len(values) * (1.0 + spare)))
        self.data = np.empty((capacity,) + values.shape[1:], values.dtype)
        self.data[:len(values)] = values
        self.n = len(values)

    @property
    def view(self) -> np.ndarray:
        return self.data[:self.n]

    def append(self, values) -> None:
        count = len(values)
        self.reserve(count)[self.n:self.n + count] = values
        self.n += count

    def reserve(self, count: int) -> np.ndarray:
        """Room for ``count`` more rows (the capacity doubles when short); returns ``data``, for a
        kernel to write rows n .. n + count - 1 before the caller adds ``count`` to ``n``."""
        if self.n + count > len(self.data):
            grown = np.empty((max(2 * len(self.data), self.n + count),) + self.data.shape[1:], self.data.dtype)
            grown[:self.n] = self.data[:self.n]
            self.data = grown
        return self.data

    def truncate(self, n: int) -> None:
        """Forget the rows from ``n`` on (undo of an append)."""
        self.n = n
