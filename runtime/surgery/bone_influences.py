"""Which bones influence the faces under each node of a BVH, and with what weights: what the posed
bounds of ``posed_bounds.py`` carry a node's rest box by.

Per node: a bone *mask* (the bones of weight != 0 on some vertex under it), and a *weight table* that
keeps, for up to ``TABLE`` bones, the lowest and the highest weight each has on the vertices under the
node (0 on a vertex it does not influence). Masks are (N, W) uint64, bone b in word b // 64, bit
b % 64; a node's children have larger indices than the node (top-down builds and leaf splits both
append), so one backward sweep computes every node (``tree_influences``), and an edit of a tree
recomputes its changed nodes and their ancestors (``refresh_influences``).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import types

from .._shared.jit import F2, I1, I2, U2, helper, i8, kernel, record
from ..tolerances import tol
from .bvh_build import N1

__all__ = ["Influences", "INFLUENCES", "TABLE", "NO_BONE", "OVERFLOW", "WEIGHT_STEPS", "tree_influences",
           "refresh_influences", "weight_summary", "posed_scale"]

#: bones per node whose weights the weight table bounds (past them: the mask's bound only)
TABLE = 4
#: a table slot that holds no bone, and a node whose bones overflow its table (or whose bone index or
#: weight the table cannot hold)
NO_BONE, OVERFLOW = -1, -2
#: the table holds weights in 16 bits, in steps of 1 / WEIGHT_STEPS rounded outwards (floor for the lowest,
#: ceil for the highest), so that its bounds hold
WEIGHT_STEPS = 65535
#: table arrays: bone ids (int16) and weights in steps (uint16), 24 bytes a node for TABLE = 4
H2, Q2 = types.int16[:, ::1], types.uint16[:, ::1]


class Influences(NamedTuple):
    """The bones under each node of a tree: masks (N, W) uint64, and the weight table: bones (N, TABLE)
    int16 (NO_BONE in unused slots; OVERFLOW in slot 0 when the node has more bones) with the lowest and
    highest weight each has on the vertices under the node (0 on a vertex it does not influence),
    (N, TABLE) uint16 each in 1 / WEIGHT_STEPS, rounded outwards."""

    masks: np.ndarray
    bones: np.ndarray
    lows: np.ndarray
    highs: np.ndarray


#: the numba type of ``Influences``
INFLUENCES = record(U2, H2, Q2, Q2)


@helper
def _add_bone(influences, node, b, low, high, fresh):
    """Bone b with weights from ``low`` to ``high`` (in steps; high > WEIGHT_STEPS: weights the table
    cannot hold) on a vertex (or a child) under ``node``, into its mask and weight table; ``fresh``:
    nothing under the node was added before (else a bone new to the table had weight 0 there)."""
    masks, bones, lows, highs = influences
    masks[node, b >> 6] |= np.uint64(1) << np.uint64(b & 63)
    if bones[node, 0] == OVERFLOW:
        return
    if b > 32767 or high > WEIGHT_STEPS:
        bones[node, 0] = OVERFLOW
        return
    for j in range(TABLE):
        if bones[node, j] == b:
            lows[node, j], highs[node, j] = min(lows[node, j], low), max(highs[node, j], high)
            return
        if bones[node, j] == NO_BONE:
            bones[node, j], lows[node, j], highs[node, j] = b, low if fresh else 0, high
            return
    bones[node, 0] = OVERFLOW


@helper
def _absent_is_zero(influences, node, other_bones, other_count):
    """The table's bones of ``node`` that are not among ``other_bones[:other_count]`` (what the last
    vertex or child added had) reach down to weight 0."""
    bones, lows = influences[1], influences[2]
    for j in range(TABLE):
        if bones[node, j] < 0:
            continue
        found = False
        for i in range(other_count):
            found = found or other_bones[i] == bones[node, j]
        if not found:
            lows[node, j] = 0


@helper
def _node_influences(influences, node, left, right, start, count, order, faces, joints, weights, n_bones, had):
    """Recompute row ``node`` of ``influences``: from its live faces' vertices (a leaf: the bones of
    weight != 0, index in range), or from its children (``had``: room for TABLE and k bones)."""
    masks, bones, lows, highs = influences
    for w in range(masks.shape[1]):
        masks[node, w] = np.uint64(0)
    for j in range(TABLE):
        bones[node, j], lows[node, j], highs[node, j] = NO_BONE, 0, 0
    fresh = True
    if left[node] >= 0:
        for child in (left[node], right[node]):
            for w in range(masks.shape[1]):
                masks[node, w] |= masks[child, w]
            if bones[child, 0] == OVERFLOW:
                bones[node, 0] = OVERFLOW
            n_had = 0
            for j in range(TABLE):
                if bones[child, j] >= 0:
                    _add_bone(influences, node, bones[child, j], lows[child, j], highs[child, j], fresh)
                    had[n_had] = bones[child, j]
                    n_had += 1
            _absent_is_zero(influences, node, had, n_had)
            fresh = False
        return
    for s in range(start[node], start[node] + count[node]):
        for c in range(3):
            v = faces[order[s], c]
            n_had = 0
            for k in range(joints.shape[1]):
                b, w = joints[v, k], weights[v, k]
                if w != 0.0 and 0 <= b < n_bones:
                    high = WEIGHT_STEPS + 1 if not 0.0 <= w <= 1.0 else math.ceil(w * WEIGHT_STEPS)
                    for i in range(n_had):
                        if had[i] == b:       # a bone listed twice: its weight is the sum, past the table
                            high = WEIGHT_STEPS + 1
                    _add_bone(influences, node, b, math.floor(max(w, 0.0) * WEIGHT_STEPS), high, fresh)
                    had[n_had] = b
                    n_had += 1
            _absent_is_zero(influences, node, had, n_had)
            fresh = False


def tree_influences(left, right, start, count, order, faces, joints, weights, n_nodes, n_bones, n_rows) -> tuple:
    """``Influences`` (as a tuple, n_rows >= n_nodes rows) of the tree's first ``n_nodes`` nodes, for
    faces (F, 3) over vertices with joints and weights (n, k); ``order`` the tree's leaf order. The rows
    past n_nodes are room for a tree that grows, allocated (by numpy: zero pages) but not written, so
    not resident until used."""
    influences = (np.zeros((n_rows, (max(n_bones, 1) + 63) // 64), np.uint64), np.zeros((n_rows, TABLE), np.int16),
                  np.zeros((n_rows, TABLE), np.uint16), np.zeros((n_rows, TABLE), np.uint16))
    _fill_influences(influences, left, right, start, count, order, faces, joints, weights, n_nodes, n_bones)
    return influences


@kernel((INFLUENCES, N1, N1, N1, N1, N1, I2, I2, F2, i8, i8), cost=0.8)
def _fill_influences(influences, left, right, start, count, order, faces, joints, weights, n_nodes, n_bones):
    """Rows 0 .. n_nodes - 1 of ``influences`` (``tree_influences``), children before parents."""
    had = np.empty(TABLE + joints.shape[1], np.int64)
    for node in range(n_nodes - 1, -1, -1):
        _node_influences(influences, node, left, right, start, count, order, faces, joints, weights, n_bones, had)


@helper
def _same_row(influences, node, saved):
    """Whether row ``node`` of ``influences`` equals ``saved`` (a copy of it, as arrays)."""
    masks, bones, lows, highs = influences
    same = True
    for w in range(masks.shape[1]):
        same = same and saved[0][w] == masks[node, w]
    for j in range(TABLE):
        same = same and saved[1][j] == bones[node, j] and saved[2][j] == lows[node, j] and saved[3][j] == highs[node, j]
    return same


@kernel((INFLUENCES, N1, N1, N1, N1, N1, N1, I2, I2, F2, I1, i8), cost=0.8)
def refresh_influences(influences, left, right, parent, start, count, order, faces, joints, weights, dirty, n_bones):
    """Recompute the influences of the ``dirty`` nodes (k,) distinct, of a tree whose faces changed (the leaves
    of the faces that came, went or moved, and the nodes a split made), then their ancestors up to the
    first that keeps them: they stay exact over the live faces."""
    masks, bones, lows, highs = influences
    had = np.empty(TABLE + joints.shape[1], np.int64)
    for i in range(dirty.shape[0]):
        _node_influences(influences, dirty[i], left, right, start, count, order, faces, joints, weights, n_bones, had)
    saved = (np.empty(masks.shape[1], np.uint64), np.empty(TABLE, np.int16), np.empty(TABLE, np.uint16),
             np.empty(TABLE, np.uint16))
    for i in range(dirty.shape[0]):
        node = parent[dirty[i]]
        while node >= 0:
            for w in range(masks.shape[1]):
                saved[0][w] = masks[node, w]
            for j in range(TABLE):
                saved[1][j], saved[2][j], saved[3][j] = bones[node, j], lows[node, j], highs[node, j]
            _node_influences(influences, node, left, right, start, count, order, faces, joints, weights, n_bones, had)
            if _same_row(influences, node, saved):
                break
            node = parent[node]


@kernel((I2, F2, i8), cost=0.2)
def _weight_summary(joints, weights, n_bones):
    """(B,) bool the bones that influence some vertex (weight != 0, index in range), and the largest
    |sum of a row's weights - 1|, in one pass (numpy's unique and row sums made arrays of the mesh's size)."""
    used = np.zeros(n_bones, np.bool_)
    slack = 0.0
    for v in range(joints.shape[0]):
        total = 0.0
        for k in range(joints.shape[1]):
            total += weights[v, k]
            if weights[v, k] != 0.0 and 0 <= joints[v, k] < n_bones:
                used[joints[v, k]] = True
        slack = max(slack, abs(total - 1.0))
    return used, slack


def weight_summary(joints, weights, n_bones: int) -> tuple:
    """(used (u,) int64 the bones that influence some vertex, increasing; the relative padding of a
    posed box: ``tol.box_padding`` plus how far the weight rows' sums are from 1, since a blend of
    weights that sum to s lies in s times the convex hull, not in it). A stroke's new vertices take
    their bones from the vertices they lie between, and their weights sum to 1: they change neither."""
    used, slack = _weight_summary(joints, weights, n_bones)
    return np.flatnonzero(used).astype(np.int64), tol.box_padding + float(slack)


def posed_scale(affines, used) -> float:
    """The largest scale (column norm of a 3x4 map's linear part) of the bones ``used`` (u,): how much
    larger than at rest the posed surface can be, which scales a posed stroke's tolerances."""
    if len(used) == 0:
        return 1.0
    linear = affines[used].reshape(-1, 3, 4)[:, :, :3]
    return float(np.sqrt((linear * linear).sum(axis=1).max()))
