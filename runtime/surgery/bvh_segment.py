"""The tests the BVH queries are made of (``bvh.py``): a segment against a node's box (the slab test,
and within a reach of it), the segment–triangle test, and the traversal stack's push.

Segment–triangle test: the watertight test of Woop, Benthin and Wald (JCGT 2(1), 2013), two-sided
(either face orientation counts). A segment through an edge or a vertex shared by several triangles
hits at least one of them, so a scalpel cannot slip between two faces.
"""
from __future__ import annotations

import numpy as np

from .._shared.jit import helper


@helper
def _segment_box(lo, hi, a, d, t_max):
    """Whether a + t d, t in [0, t_max], meets the box [lo, hi]; returns (hit, t_entry)."""
    t0, t1 = 0.0, t_max
    for k in range(3):
        if d[k] == 0.0:
            if a[k] < lo[k] or a[k] > hi[k]:
                return False, 0.0
            continue
        inv = 1.0 / d[k]
        u = (lo[k] - a[k]) * inv
        v = (hi[k] - a[k]) * inv
        if u > v:
            u, v = v, u
        t0 = max(t0, u)
        t1 = min(t1, v)
        if t0 > t1:
            return False, 0.0
    return True, t0


@helper
def _near_box(lo, hi, a, d, t_max, reach):
    """Whether a + t d, t in [0, t_max], comes within ``reach`` of the box [lo, hi] in every axis."""
    t0, t1 = 0.0, t_max
    for k in range(3):
        low, high = lo[k] - reach, hi[k] + reach
        if d[k] == 0.0:
            if a[k] < low or a[k] > high:
                return False
            continue
        u, v = (low - a[k]) / d[k], (high - a[k]) / d[k]
        t0, t1 = max(t0, min(u, v)), min(t1, max(u, v))
        if t0 > t1:
            return False
    return True


@helper
def _push_children(stack, top, left, right):
    """Push a node's children on a traversal stack (the left one on top: visited first), growing it
    when full; returns (stack, top)."""
    if top + 3 > stack.shape[0]:
        stack = np.concatenate((stack, np.empty_like(stack)))
    stack[top + 1], stack[top + 2] = right, left
    return stack, top + 2


@helper
def _watertight(positions, faces, f, a, kx, ky, kz, sx, sy, sz):
    """Woop–Benthin–Wald test of the segment a + t d (sheared frame kx, ky, kz, sx, sy, sz) against
    the triangle positions[faces[f]]; two-sided. Returns t (may lie outside [0, 1]) or NaN for a miss."""
    p, q, r = faces[f, 0], faces[f, 1], faces[f, 2]
    ax = positions[p, kx] - a[kx]
    ay = positions[p, ky] - a[ky]
    az = positions[p, kz] - a[kz]
    bx = positions[q, kx] - a[kx]
    by = positions[q, ky] - a[ky]
    bz = positions[q, kz] - a[kz]
    cx = positions[r, kx] - a[kx]
    cy = positions[r, ky] - a[ky]
    cz = positions[r, kz] - a[kz]
    ax, ay = ax - sx * az, ay - sy * az
    bx, by = bx - sx * bz, by - sy * bz
    cx, cy = cx - sx * cz, cy - sy * cz
    u = cx * by - cy * bx
    v = ax * cy - ay * cx
    w = bx * ay - by * ax
    if (u < 0.0 or v < 0.0 or w < 0.0) and (u > 0.0 or v > 0.0 or w > 0.0):
        return np.nan
    det = u + v + w
    if det == 0.0:
        return np.nan    # the segment lies in the triangle's plane: no transversal crossing
    return (u * sz * az + v * sz * bz + w * sz * cz) / det


@helper
def _shear(d):
    """The watertight test's per-segment constants: the dominant axis kz and the shear."""
    kz = 0
    if abs(d[1]) > abs(d[kz]):
        kz = 1
    if abs(d[2]) > abs(d[kz]):
        kz = 2
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    if d[kz] < 0.0:
        kx, ky = ky, kx     # keep the winding, so that the sign test stays consistent
    return kx, ky, kz, d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]
