"""Rows of a per-vertex array gathered into another in compiled code (a cut's halves, a drill's result):
``out[i] = values[src[i]]``, unrolled for the widths of positions and normals (3) and of joints and
weights (4), about twice as fast there as a loop over an unknown width."""
from __future__ import annotations

from .._shared.jit import helper


@helper
def gather_rows(values, src, out):
    """out[i] = values[src[i]] for i < len(src) (values (n, c), src (a,), out (>= a, c))."""
    c = values.shape[1]
    if c == 3:
        for i in range(src.shape[0]):
            s = src[i]
            out[i, 0] = values[s, 0]
            out[i, 1] = values[s, 1]
            out[i, 2] = values[s, 2]
    elif c == 4:
        for i in range(src.shape[0]):
            s = src[i]
            out[i, 0] = values[s, 0]
            out[i, 1] = values[s, 1]
            out[i, 2] = values[s, 2]
            out[i, 3] = values[s, 3]
    else:
        for i in range(src.shape[0]):
            for j in range(c):
                out[i, j] = values[src[i], j]
