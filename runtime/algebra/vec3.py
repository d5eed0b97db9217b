"""3-vector and row helpers for kernels (scalar loops: numba compiles every array expression into a
kernel of its own)."""
import math

import numpy as np
from .._shared.jit import helper


# 3-vector helpers: scalar loops, because numba compiles every array expression (``a - b``,
# ``np.sum(x ** 2)``) into a kernel of its own, a fraction of a second of compile time each
@helper
def _cross(u, v):
    out = np.empty(3)
    out[0] = u[1] * v[2] - u[2] * v[1]
    out[1] = u[2] * v[0] - u[0] * v[2]
    out[2] = u[0] * v[1] - u[1] * v[0]
    return out


@helper
def _sub(p, q):
    """p - q (3,)"""
    out = np.empty(3)
    for k in range(3):
        out[k] = p[k] - q[k]
    return out


@helper
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@helper
def _norm(u):
    return math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])


@helper
def _distance(p, q):
    """|p - q| of two (3,) points"""
    return math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2)


# Rows are copied by loops: numba's array-into-array assignment (``dst[i] = src``) compiles its
# shape-mismatch message (string formatting), seconds of compile time in every process.
@helper
def _set_row(dst, i, src):
    """dst[i] = src (c,)"""
    for c in range(src.shape[0]):
        dst[i, c] = src[c]


@helper
def _copy_row(dst, i, src, j):
    """dst[i] = src[j] (no view of the row: this runs for every vertex)"""
    for c in range(src.shape[1]):
        dst[i, c] = src[j, c]
