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
box meets the query (a blade segment within a reach, or the region's box and plane slab: the stroke's
own queries, ``_meets``), and skins the vertices of the leaves it meets (a stamp per vertex) with the
blend loop of ``cgaskin.skin`` (the same numbers). Every node the stroke's query then visits is a child
of a node whose posed box met that query, so its own box was computed.

That bound is loose where weights blend over a long stretch (a vertex with 0.3 of the upper arm and 0.7
of the forearm is carried by both, far apart). So each node also keeps the lowest and highest weight
each of its bones has on it, for up to ``TABLE`` bones: with r one of them, a skinned vertex is
A_r v + Σ_k w_k (A_k - A_r) v (weights summing to 1), so it lies in A_r's carried box plus, per other
bone k, [l_k, h_k] times the box carried by A_k - A_r: where the weights vary little across a node (a
leaf), the bound is about the node's own size. The posed box is the intersection of both bounds (both
hold); a node with more bones keeps the first.

The masks and weight tables are ``bone_influences.py``'s.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._shared.jit import F1, F2, I1, I2, f8, helper, kernel, record
from .._shared.memory import sparse_zeros
from ..generated.skinning import skin_blend
from .bone_influences import INFLUENCES, TABLE, WEIGHT_STEPS
from .bvh import BVH_ARRAYS, BVHArrays, _near_box, _push_children
from .bvh_build import N1

__all__ = ["Posing", "POSING", "PosedScratch", "no_posing", "pose_region"]


class Posing(NamedTuple):
    """What ``_pose_region`` reads and writes besides the posed tree (a stroke's BVHArrays, whose node
    boxes and positions it fills).

    rest_lo, rest_hi : (N, 3) float64 the rest tree's padded node boxes ; influences : ``Influences`` ;
    node_stamp (N,), vertex_stamp (n,) int64: which nodes and vertices hold this pose's values ;
    vertices (n, 3), joints (n, k), weights (n, k) : the rest mesh ; affines (B, 12) : the pose's bone
    maps ; state (2,) int64 : (``STAMP`` of this pose, ``ACTIVE``: 1 when posing is active, 0 when the
    surface is as stored) ; pad (1,) float64 : relative padding of a posed box
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


#: the entries of ``Posing.state``
STAMP, ACTIVE = 0, 1

#: the numba type of ``Posing`` (as a plain tuple)
POSING = record(F2, F2, INFLUENCES, I1, I1, F2, I2, F2, F2, I1, F1)


def no_posing() -> tuple:
    """The inactive ``Posing`` of a surface torn as stored (empty arrays)."""
    f2, i1 = np.empty((0, 3)), np.zeros(0, np.int64)
    influences = (np.zeros((0, 1), np.uint64), np.zeros((0, TABLE), np.int16), np.zeros((0, TABLE), np.uint16),
                  np.zeros((0, TABLE), np.uint16))
    return tuple(Posing(f2, f2, influences, i1, i1, f2, np.zeros((0, 4), np.int64), np.zeros((0, 4)),
                        np.zeros((0, 12)), state=np.zeros(2, np.int64), pad=np.zeros(1)))


# ---- posed boxes and positions, where a query reaches ----------------------------------------------
#: ``_carried``'s ref for "no reference bone" (an int64 like the bone ids it is passed, so that numba
#: compiles one variant rather than one per argument type and literal)
NO_BONE = np.int64(-1)


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
    rest_lo, rest_hi, (masks, bones, lows, highs), _, _, _, _, _, affines, _, relative_pad = posing
    pad = relative_pad[0]
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
                    c, h = _carried(affines, b, NO_BONE, rest_lo, rest_hi, node, r)
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
            c, h = _carried(affines, np.int64(bones[node, ref]), NO_BONE, rest_lo, rest_hi, node, r)
            low, high = c - h, c + h
            for j in range(TABLE):
                if j != ref and bones[node, j] >= 0:
                    c, h = _carried(affines, np.int64(bones[node, j]), np.int64(bones[node, ref]), rest_lo, rest_hi,
                                    node, r)
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
def _meets(lo, hi, node, query, a, b, d, reach):
    """Whether node's box [lo, hi] meets the query: a segment a -> b (d = b - a) within ``reach``
    (``query`` (0,): the guess's own test, ``bvh._near_box``), or the box [a, b] where it holds points
    within ``reach`` of the plane ``query`` (4,) (n, d: the signed distance n.x - d; an empty plane, all
    zero, takes the whole box)."""
    if query.shape[0] == 0:
        return _near_box(lo[node], hi[node], a, d, 1.0, reach)
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
    _, _, _, node_stamp, vertex_stamp, vertices, joints, weights, affines, state, _ = posing
    if state[ACTIVE] == 0:
        return
    lo, hi, left, right, start, count, order, positions, faces = bvh
    stamp, d = state[STAMP], b - a
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
        if not _meets(lo, hi, node, query, a, b, d, reach):
            continue
        if left[node] >= 0:
            stack, top = _push_children(stack, top, left[node], right[node])
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


@kernel((BVH_ARRAYS, POSING, F1, F1, F1, f8), cost=1.0)
def pose_region(bvh, posing, query, a, b, reach):
    """``_pose_region`` from Python (a session's drill poses its region with it; tests check the bounds)."""
    _pose_region(bvh, posing, query, a, b, reach)


@helper
def _pose_blades(bvh, posing, blades, reach):
    """``_pose_region`` for both blade segments (handle -> tip, (4, 3)) within ``reach``."""
    _pose_region(bvh, posing, np.empty(0), blades[0], blades[1], reach)
    _pose_region(bvh, posing, np.empty(0), blades[2], blades[3], reach)


@kernel((I1, N1, I1), cost=0.1)
def _forget_nodes(node_stamp, parents, nodes):
    """Clear the stamps of ``nodes`` (k,) and of all their ancestors (their boxes or influences changed)."""
    for i in range(nodes.shape[0]):
        node = nodes[i]
        while 0 <= node < node_stamp.shape[0]:
            node_stamp[node] = 0
            node = parents[node]


class PosedScratch:
    """The arrays a surface's strokes in poses write (posed node boxes, positions and their stamps),
    grown as the tree and the mesh grow. A ``view`` in another pose than the last one is a new stamp;
    in the same pose it keeps what earlier strokes posed, less what ``forget`` was told changed since
    (a session in one pose poses each part once). Rows are allocated, not written: only what strokes
    reach becomes resident (``sparse_zeros``)."""

    def __init__(self):
        self._stamp, self._affines = 0, None
        self._lo = self._hi = self._positions = np.empty((0, 3))
        self._node_stamp = self._vertex_stamp = np.zeros(0, np.int64)

    def reset(self) -> None:
        """Nothing posed holds any more (the tree was built anew)."""
        self._affines = None

    def forget(self, nodes, parents, rows) -> None:
        """The tree's ``nodes`` (k,) int64 (with their ancestors, ``parents`` (N,) int32) and the mesh's
        ``rows`` (r,) int64 changed: pose them again when a query reaches them."""
        if self._affines is None:
            return
        _forget_nodes(self._node_stamp, parents, nodes)
        self._vertex_stamp[rows[rows < len(self._vertex_stamp)]] = 0

    def view(self, tree, n_nodes, influences, vertices, joints, weights, affines, pad) -> tuple:
        """(BVHArrays of the posed tree as a tuple, ``Posing`` as a tuple) for ``tree`` (the rest BVH's
        arrays: lo, hi, left, right, start, count, order, positions, faces; ``n_nodes`` of its rows in
        use) with its ``Influences`` (a tuple), the rest mesh (n rows) and bone maps ``affines`` (B, 12)."""
        n = len(vertices)
        # (written where strokes reach, a few thousand scattered rows: 4 kB pages, not huge ones)
        if len(self._lo) < n_nodes:
            size = max(n_nodes, len(self._lo) * 3 // 2)
            self._lo, self._hi, self._node_stamp = (sparse_zeros((size, 3)), sparse_zeros((size, 3)),
                                                    sparse_zeros(size, np.int64))
        if len(self._positions) < n:
            size = max(n, len(self._positions) * 3 // 2)
            self._positions, self._vertex_stamp = sparse_zeros((size, 3)), sparse_zeros(size, np.int64)
        if self._affines is None or not np.array_equal(affines, self._affines):
            self._stamp, self._affines = self._stamp + 1, affines.copy()
        positions = self._positions[:n]
        rest = BVHArrays(*tree)
        bvh = rest._replace(lo=self._lo, hi=self._hi, positions=positions)
        state = np.empty(2, np.int64)
        state[STAMP], state[ACTIVE] = self._stamp, 1
        posing = Posing(rest.lo, rest.hi, influences, self._node_stamp, self._vertex_stamp[:n], vertices, joints,
                        weights, affines, state, np.array([pad]))
        return tuple(bvh), tuple(posing)
