"""Where a skinned surface lies in any pose, without skinning it: bone-carried bounds per BVH node.

A vertex skinned by linear blending, Σ w_k A_k v with w_k >= 0 and Σ w_k = 1, lies in the convex hull
of its rest position carried by each of its bones' maps A_k. So a node of a BVH built over the *rest*
positions bounds its faces in every pose by its rest box carried by each bone that influences a vertex
under it, the node's *bone mask* (Kavan & Žára, "Fast collision detection for skeletally deformable
models", 2005; James & Pai's BD-Tree, 2004). A box [c - h, c + h] carried by a 3x4 map (M, t) lies in
[M c + t - |M| h, M c + t + |M| h]; a dilating map scales it with the rest. The posed box of a node is
the bounding box of those boxes over its bones, padded by ``tol.box_padding`` of its size (rounding,
and weights that sum to 1 only to float precision).

A stroke in a new pose then poses only what the blade can reach (``_pose_region``): from the root it
computes the posed box of every node it visits (once per pose: a stamp per node), descends where the
box meets the query box, and skins the vertices of the leaves it reaches (a stamp per vertex) with
the blend loop of ``cgaskin.skin`` (the same numbers). Every node a later query of the stroke visits
is a child of a node whose posed box met a box inside the query box, so its own box was computed.

That bound is loose where weights blend over a long stretch (a vertex with 0.3 of the upper arm and 0.7
of the forearm is carried by both, far apart). So each node also keeps the lowest and highest weight
each of its bones has on it, for up to ``TABLE`` bones: with r one of them, a skinned vertex is
A_r v + Σ_k w_k (A_k - A_r) v (weights summing to 1), so it lies in A_r's carried box plus, per other
bone k, [l_k, h_k] times the box carried by A_k - A_r: where the weights vary little across a node (a
leaf), the bound is about the node's own size. The posed box is the intersection of both bounds (both
hold); a node with more bones keeps the first.

Masks are (N, W) uint64, bone b in word b // 64, bit b % 64; a node's children have larger indices
than the node (top-down builds and leaf splits both append), so one backward sweep computes them all.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import types

from .._shared.jit import F1, F2, I1, I2, U2, helper, i8, kernel, record
from ..generated.skinning import skin_blend
from .bvh_build import N1

__all__ = ["Influences", "Posing", "POSING", "PosedScratch", "bone_masks", "refresh_masks", "used_bones",
           "posed_scale", "no_posing", "pose_region"]


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


class Posing(NamedTuple):
    """What ``_pose_region`` reads and writes besides the posed tree (a stroke's BVHArrays, whose node
    boxes and positions it fills).

    rest_lo, rest_hi : (N, 3) float64 the rest tree's padded node boxes ; influences : ``Influences`` ; node_stamp (N,), vertex_stamp (n,) int64: which nodes and vertices hold this pose's values ;
    vertices (n, 3), joints (n, k), weights (n, k) : the rest mesh ; affines (B, 12) : the pose's bone
    maps ; state (2,) int64 : [stamp of this pose, 1 when posing is active (0: the surface is as stored)] ;
    pad (1,) float64 : relative padding of a posed box
    """

    rest_lo: np.ndarray
    rest_hi: np.ndarray
    influences: tuple
    node_stamp: np.ndarray
    vertex_stamp: np.ndarray
    vertices: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    affines: np.ndarray
    state: np.ndarray
    pad: np.ndarray


#: the numba type of ``Posing`` (as a plain tuple)
POSING = record(F2, F2, INFLUENCES, I1, I1, F2, I2, F2, F2, I1, F1)


def no_posing() -> tuple:
    """The inactive ``Posing`` of a surface torn as stored (empty arrays)."""
    f2, i1 = np.empty((0, 3)), np.zeros(0, np.int64)
    return (f2, f2, (np.zeros((0, 1), np.uint64), np.zeros((0, TABLE), np.int16), np.zeros((0, TABLE), np.uint16),
                      np.zeros((0, TABLE), np.uint16)), i1, i1, f2, np.zeros((0, 4), np.int64), np.zeros((0, 4)),
            np.zeros((0, 12)), np.zeros(2, np.int64), np.zeros(1))


# ---- bone masks and weight tables ----------------------------------------------------------------
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


@kernel((N1, N1, N1, N1, N1, I2, I2, F2, i8, i8, i8), cost=0.8)
def bone_masks(left, right, start, count, order, faces, joints, weights, n_nodes, n_bones, n_rows):
    """``Influences`` (as a tuple, n_rows rows) of the tree's first ``n_nodes`` nodes, for faces (F, 3)
    over vertices with joints and weights (n, k); ``order`` the tree's leaf order."""
    influences = (np.zeros((n_rows, (max(n_bones, 1) + 63) // 64), np.uint64), np.full((n_rows, TABLE), NO_BONE, np.int16),
                  np.zeros((n_rows, TABLE), np.uint16), np.zeros((n_rows, TABLE), np.uint16))
    had = np.empty(TABLE + joints.shape[1], np.int64)
    for node in range(n_nodes - 1, -1, -1):
        _node_influences(influences, node, left, right, start, count, order, faces, joints, weights, n_bones, had)
    return influences


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
def refresh_masks(influences, left, right, parent, start, count, order, faces, joints, weights, dirty, n_bones):
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


def used_bones(joints, weights, n_bones: int) -> np.ndarray:
    """(u,) int64: the bones that influence some vertex (weight != 0), increasing. (A stroke's new
    vertices take their bones from the vertices they lie between: they add none.)"""
    bones = np.unique(np.asarray(joints)[np.asarray(weights) != 0])
    return bones[(bones >= 0) & (bones < n_bones)].astype(np.int64)


def posed_scale(affines, used) -> float:
    """The largest scale (column norm of a 3x4 map's linear part) of the bones ``used`` (u,): how much
    larger than at rest the posed surface can be, which scales a posed stroke's tolerances."""
    if len(used) == 0:
        return 1.0
    linear = affines[used].reshape(-1, 3, 4)[:, :, :3]
    return float(np.sqrt((linear * linear).sum(axis=1).max()))


# ---- posed boxes and positions, where a query reaches ----------------------------------------------
@helper
def _carried(affines, b, ref, rest_lo, rest_hi, node, r):
    """(centre, half extent) along axis r of node's rest box carried by bone b's map less bone ref's
    (ref < 0: b's map itself)."""
    c, h = affines[b, 4 * r + 3], 0.0
    if ref >= 0:
        c -= affines[ref, 4 * r + 3]
    for k in range(3):
        m = affines[b, 4 * r + k] if ref < 0 else affines[b, 4 * r + k] - affines[ref, 4 * r + k]
        c += m * (0.5 * (rest_lo[node, k] + rest_hi[node, k]))
        h += abs(m) * (0.5 * (rest_hi[node, k] - rest_lo[node, k]))
    return c, h


@helper
def _posed_box(bvh, posing, node):
    """Write node's posed box into the posed tree (bvh's lo, hi) from its rest box, influences and the
    bone maps: the mask's bound, cut by the weight table's where the node has one (module docstring;
    an empty rest box, or no bone, gives an empty box)."""
    lo, hi = bvh[0], bvh[1]
    rest_lo, rest_hi, (masks, bones, lows, highs), affines, pad = (posing[0], posing[1], posing[2], posing[8],
                                                                   posing[10][0])
    for k in range(3):
        lo[node, k], hi[node, k] = np.inf, -np.inf
    if not rest_lo[node, 0] <= rest_hi[node, 0]:
        return
    for w in range(masks.shape[1]):
        bits = masks[node, w]
        b = 64 * w
        while bits != np.uint64(0):
            if bits & np.uint64(1):
                for r in range(3):
                    c, h = _carried(affines, b, -1, rest_lo, rest_hi, node, r)
                    lo[node, r], hi[node, r] = min(lo[node, r], c - h), max(hi[node, r], c + h)
            bits = bits >> np.uint64(1)
            b += 1
    if not lo[node, 0] <= hi[node, 0]:
        return
    if bones[node, 0] >= 0:
        ref = 0                       # the bone with the largest lowest weight: the others' terms are small
        for j in range(1, TABLE):
            if bones[node, j] >= 0 and lows[node, j] > lows[node, ref]:
                ref = j
        for r in range(3):
            c, h = _carried(affines, bones[node, ref], -1, rest_lo, rest_hi, node, r)
            low, high = c - h, c + h
            for j in range(TABLE):
                if j != ref and bones[node, j] >= 0:
                    c, h = _carried(affines, bones[node, j], bones[node, ref], rest_lo, rest_hi, node, r)
                    w0, w1 = lows[node, j] / WEIGHT_STEPS, highs[node, j] / WEIGHT_STEPS
                    low += min(w0 * (c - h), w1 * (c - h))
                    high += max(w0 * (c + h), w1 * (c + h))
            lo[node, r], hi[node, r] = max(lo[node, r], low), min(hi[node, r], high)
    size = 0.0
    for k in range(3):
        size = max(size, max(abs(lo[node, k]), abs(hi[node, k])) + (hi[node, k] - lo[node, k]))
    for k in range(3):
        lo[node, k] -= pad * size
        hi[node, k] += pad * size


@helper
def _meets(lo, hi, node, query, a, b, reach):
    """Whether node's box [lo, hi] meets the query: a segment a -> b within ``reach`` (``query`` (0,)),
    or the box [a, b] where it holds points within ``reach`` of the plane ``query`` (4,) (n, d: the
    signed distance n.x - d; an empty plane, all zero, takes the whole box)."""
    if query.shape[0] == 0:
        t0, t1 = 0.0, 1.0
        for k in range(3):
            low, high, d = lo[node, k] - reach, hi[node, k] + reach, b[k] - a[k]
            if d == 0.0:
                if a[k] < low or a[k] > high:
                    return False
                continue
            u, v = (low - a[k]) / d, (high - a[k]) / d
            t0, t1 = max(t0, min(u, v)), min(t1, max(u, v))
            if t0 > t1:
                return False
        return True
    smin = smax = -query[3]
    for k in range(3):
        if lo[node, k] > b[k] or hi[node, k] < a[k]:
            return False
        u, v = query[k] * lo[node, k], query[k] * hi[node, k]
        smin, smax = smin + min(u, v), smax + max(u, v)
    return smin <= reach and smax >= -reach


@helper
def _pose_region(bvh, posing, query, a, b, reach):
    """Pose what a query reaches (``_meets``): the posed box of every node visited from the root
    (descending where it meets the query) and the skinned positions of the vertices of the leaves it
    meets, in bvh (BVHArrays as a tuple: lo, hi and positions are written). Nothing when posing is not
    active."""
    node_stamp, vertex_stamp, vertices, joints, weights, affines, state = (posing[3], posing[4], posing[5],
                                                                          posing[6], posing[7], posing[8], posing[9])
    if state[1] == 0:
        return
    lo, hi, left, right, start, count, order, positions, faces = bvh
    stamp = state[0]
    todo = np.empty(64, np.int64)           # the vertices to skin, in one call of the blend at the end
    n_todo = 0
    stack = np.empty(128, np.int64)
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        if node_stamp[node] != stamp:
            _posed_box(bvh, posing, node)
            node_stamp[node] = stamp
        if not _meets(lo, hi, node, query, a, b, reach):
            continue
        if left[node] >= 0:
            if top + 3 > stack.shape[0]:
                stack = np.concatenate((stack, np.empty_like(stack)))
            stack[top + 1], stack[top + 2] = right[node], left[node]
            top += 2
            continue
        for s in range(start[node], start[node] + count[node]):
            for c in range(3):
                v = faces[order[s], c]
                if vertex_stamp[v] != stamp:
                    vertex_stamp[v] = stamp
                    if n_todo == todo.shape[0]:
                        todo = np.concatenate((todo, np.empty_like(todo)))
                    todo[n_todo] = v
                    n_todo += 1
    if n_todo == 0:
        return
    rest, bones, blend = np.empty((n_todo, 3)), np.empty((n_todo, joints.shape[1]), np.int64), \
        np.empty((n_todo, joints.shape[1]))
    for i in range(n_todo):
        for k in range(3):
            rest[i, k] = vertices[todo[i], k]
        for k in range(joints.shape[1]):
            bones[i, k], blend[i, k] = joints[todo[i], k], weights[todo[i], k]
    skinned = np.empty((n_todo, 3))
    skin_blend(rest, bones, blend, affines, skinned)       # cgaskin.skin's loop: the same numbers
    for i in range(n_todo):
        for k in range(3):
            positions[todo[i], k] = skinned[i, k]


@kernel()
def pose_region(bvh, posing, query, a, b, reach):
    """``_pose_region`` from Python (tests check the bounds with it)."""
    _pose_region(bvh, posing, query, a, b, reach)


@helper
def _pose_blades(bvh, posing, blades, reach):
    """``_pose_region`` for both blade segments (handle -> tip, (4, 3)) within ``reach``."""
    _pose_region(bvh, posing, np.empty(0), blades[0], blades[1], reach)
    _pose_region(bvh, posing, np.empty(0), blades[2], blades[3], reach)


class PosedScratch:
    """The arrays a surface's strokes in other poses write (posed node boxes, positions and their
    stamps), grown as the tree and the mesh grow; each ``view`` is a new pose (a new stamp). Rows
    are allocated, not written: only what strokes reach becomes resident."""

    def __init__(self):
        self._stamp = 0
        self._lo = self._hi = self._positions = np.empty((0, 3))
        self._node_stamp = self._vertex_stamp = np.zeros(0, np.int64)

    def view(self, tree, n_nodes, influences, vertices, joints, weights, affines, pad) -> tuple:
        """(BVHArrays of the posed tree as a tuple, ``Posing`` as a tuple) for ``tree`` (the rest BVH's
        arrays: lo, hi, left, right, start, count, order, positions, faces; ``n_nodes`` of its rows in
        use) with its ``Influences`` (a tuple), the rest mesh (n rows) and bone maps ``affines`` (B, 12)."""
        n = len(vertices)
        if len(self._lo) < n_nodes:
            size = max(n_nodes, len(self._lo) * 3 // 2)
            self._lo, self._hi, self._node_stamp = np.empty((size, 3)), np.empty((size, 3)), np.zeros(size, np.int64)
        if len(self._positions) < n:
            size = max(n, len(self._positions) * 3 // 2)
            self._positions, self._vertex_stamp = np.empty((size, 3)), np.zeros(size, np.int64)
        self._stamp += 1
        positions = self._positions[:n]
        bvh = (self._lo, self._hi, tree[2], tree[3], tree[4], tree[5], tree[6], positions, tree[8])
        posing = (tree[0], tree[1], influences, self._node_stamp, self._vertex_stamp[:n], vertices, joints, weights,
                  affines, np.array([self._stamp, 1]), np.array([pad]))
        return bvh, posing
