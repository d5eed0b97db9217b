"""A bounding-volume hierarchy over triangles, for segment queries (the scalpel of ``cgaskin.tear``).

The paper tested the scalpel against every face, which was 99 % of its tear time. Here the faces go
into a binary BVH once per set of positions (rest positions, or the skinned positions of one pose),
and each query visits only the boxes that the segment crosses.

Build: top-down, each node split at the middle of its centroids' extent along the longest axis
(object median when that leaves one side empty), leaves of at most ``LEAF_SIZE`` triangles, in one
numba loop with an explicit stack (``bvh_build.py``). The tree holds face ids in leaf order, not
triangles: a query reads a triangle's corners as positions[faces[face]] (a per-slot copy of the
corners, 72 bytes a face, was the largest array of an editing session's BVH).

Segment–triangle test: the watertight test of Woop, Benthin and Wald (JCGT 2(1), 2013), two-sided
(either face orientation counts). A segment through an edge or a vertex shared by several triangles
hits at least one of them, so a scalpel cannot slip between two faces.

A ``TriangleBVH`` keeps the positions and faces it was built from (its own copies; ``of_checked``
and ``of_tree`` keep the caller's arrays); build another one when the positions change (a
functional tear keeps one per rig and pose: ``tear/rig_source.py``; an editing session updates a
``DynamicBVH`` in place).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._shared.checks import float_array, index_array
from .._shared.jit import F1, F2, I2, f8, helper, kernel, record
from ..errors import InvalidInputError
from ..tolerances import tol
from .bvh_build import N1, _build, _one_leaf

__all__ = ["TriangleBVH", "BVHArrays", "LEAF_SIZE"]

#: at most this many triangles per leaf (4 balances box tests against triangle tests)
LEAF_SIZE = 4
#: boxes are padded by this fraction of the scene's extent, so that rounding in the slab test never
#: culls a triangle that the triangle test (exact signs) would hit
BOX_PADDING = tol.box_padding


class BVHArrays(NamedTuple):
    """The hierarchy as the query kernels take it.

    lo, hi : (N, 3) float64 padded node boxes ; left, right : (N,) int32 children (-1 for leaves)
    start, count : (N,) int32 leaf ranges into the leaf order ; order : (s,) int32 face id of each
    leaf slot ; positions : (n, 3) float64 ; faces : (F, 3) int64 rows by face id: the corners of
    face f are positions[faces[f]]
    """

    lo: np.ndarray
    hi: np.ndarray
    left: np.ndarray
    right: np.ndarray
    start: np.ndarray
    count: np.ndarray
    order: np.ndarray
    positions: np.ndarray
    faces: np.ndarray


#: the numba type of ``BVHArrays`` (for precompile signatures)
BVH_ARRAYS = record(F2, F2, N1, N1, N1, N1, N1, F2, I2)


@kernel()
def _tree(positions, faces, one_leaf_up_to):
    """The tree fields of ``BVHArrays`` (lo, hi, left, right, start, count, order) over every face
    (m >= 1): one leaf when m <= ``one_leaf_up_to`` (for a few thousand faces, testing each one costs
    less than building a tree: a tear stroke's patch), else ``_build``'s tree, its node arrays trimmed."""
    if faces.shape[0] <= one_leaf_up_to:
        return _one_leaf(positions, faces, BOX_PADDING)
    order = np.arange(faces.shape[0]).astype(np.int32)
    # int64 arguments, not the literals numba would see: the build Python calls is then the one compiled
    lo, hi, left, right, start, count, n, _ = _build(positions, faces, order, np.int64(LEAF_SIZE), BOX_PADDING,
                                                     np.int64(0))
    return lo[:n].copy(), hi[:n].copy(), left[:n].copy(), right[:n].copy(), start[:n].copy(), count[:n].copy(), order


# ---- queries ------------------------------------------------------------------------------------
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


@kernel((BVH_ARRAYS, F1, F1), cost=1.4)
def _first_hit(bvh, a, b):
    """Smallest t in [0, 1] where segment a -> b meets a triangle of ``bvh`` (BVHArrays as a tuple);
    returns (face, t), face -1 if none."""
    node_lo, node_hi, node_left, node_right, node_start, node_count, order, positions, faces = bvh
    d = b - a
    kx, ky, kz, sx, sy, sz = _shear(d)
    best_t = np.inf
    best_i = -1
    stack = np.empty(128, np.int64)
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        hit, t_entry = _segment_box(node_lo[node], node_hi[node], a, d, min(1.0, best_t))
        if not hit:
            continue
        if node_left[node] < 0:
            for i in range(node_start[node], node_start[node] + node_count[node]):
                t = _watertight(positions, faces, order[i], a, kx, ky, kz, sx, sy, sz)
                # equal t (a segment through an edge or a vertex): the lowest face id, whatever the tree
                if t >= 0.0 and t <= 1.0 and (t < best_t or (t == best_t and order[i] < order[best_i])):
                    best_t, best_i = t, i
            continue
        # visit the nearer child first (pushed last), so that best_t shrinks early
        left, right = node_left[node], node_right[node]
        hl, tl = _segment_box(node_lo[left], node_hi[left], a, d, min(1.0, best_t))
        hr, tr = _segment_box(node_lo[right], node_hi[right], a, d, min(1.0, best_t))
        if top + 3 > stack.shape[0]:
            stack = np.concatenate((stack, np.empty_like(stack)))
        if hl and hr:
            if tl <= tr:
                stack[top + 1], stack[top + 2] = right, left
            else:
                stack[top + 1], stack[top + 2] = left, right
            top += 2
        elif hl:
            top += 1
            stack[top] = left
        elif hr:
            top += 1
            stack[top] = right
    if best_i < 0:
        return -1, np.nan
    return order[best_i], best_t


@kernel()
def _all_hits(bvh, a, b):
    """Every crossing of segment a -> b with a triangle of ``bvh`` (BVHArrays as a tuple):
    (faces (k,), t (k,)), unsorted."""
    node_lo, node_hi, node_left, node_right, node_start, node_count, order, positions, faces = bvh
    d = b - a
    kx, ky, kz, sx, sy, sz = _shear(d)
    found = np.empty(16, np.int64)
    ts = np.empty(16)
    n = 0
    stack = np.empty(128, np.int64)
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        hit, _ = _segment_box(node_lo[node], node_hi[node], a, d, 1.0)
        if not hit:
            continue
        if node_left[node] < 0:
            for i in range(node_start[node], node_start[node] + node_count[node]):
                t = _watertight(positions, faces, order[i], a, kx, ky, kz, sx, sy, sz)
                if t >= 0.0 and t <= 1.0:
                    if n == found.shape[0]:
                        found = np.concatenate((found, np.empty_like(found)))
                        ts = np.concatenate((ts, np.empty_like(ts)))
                    found[n], ts[n] = order[i], t
                    n += 1
            continue
        stack, top = _push_children(stack, top, node_left[node], node_right[node])
    return found[:n].copy(), ts[:n].copy()


@kernel((BVH_ARRAYS, F1, F1, F1, f8, f8), cost=0.8)
def _faces_near_plane(arrays, lo, hi, normal, offset, delta):
    """The live faces (unsorted: np.sort compiles for seconds; callers sort) whose triangle box meets
    the closed box [lo, hi] and whose corners' s = normal . x - offset have min(s) <= delta,
    max(s) >= -delta. arrays : ``BVHArrays`` (as a tuple), of a TriangleBVH or a DynamicBVH (whose
    ``slot_face`` is the leaf order)."""
    node_lo, node_hi, node_left, node_right, node_start, node_count, order, positions, faces = arrays
    out = np.empty(64, np.int64)
    n = top = 0
    stack = np.empty(128, np.int64)
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        # the padded box holds its triangles with room to spare for the rounding of s
        smin = smax = -offset
        meets = True
        for k in range(3):
            meets = meets and node_lo[node, k] <= hi[k] and node_hi[node, k] >= lo[k]
            u, v = normal[k] * node_lo[node, k], normal[k] * node_hi[node, k]
            smin, smax = smin + min(u, v), smax + max(u, v)
        if not meets or smin > delta or smax < -delta:
            continue
        if node_left[node] >= 0:
            stack, top = _push_children(stack, top, node_left[node], node_right[node])
            continue
        for i in range(node_start[node], node_start[node] + node_count[node]):
            s0, s1, s2 = -offset, -offset, -offset
            p, q, r = faces[order[i], 0], faces[order[i], 1], faces[order[i], 2]
            for k in range(3):
                c0, c1, c2 = positions[p, k], positions[q, k], positions[r, k]
                meets = meets and min(c0, min(c1, c2)) <= hi[k] and max(c0, max(c1, c2)) >= lo[k]
                s0, s1, s2 = s0 + normal[k] * c0, s1 + normal[k] * c1, s2 + normal[k] * c2
            if meets and min(s0, min(s1, s2)) <= delta and max(s0, max(s1, s2)) >= -delta:
                if n == out.shape[0]:
                    out = np.concatenate((out, np.empty_like(out)))
                out[n] = order[i]
                n += 1
            meets = True
    return out[:n].copy()


# ---- public object --------------------------------------------------------------------------------
class TriangleBVH:
    """A BVH over the triangles ``faces`` of the mesh at ``positions``.

    Parameters
    ----------
    positions : (n, 3) float
        Vertex positions (rest, or skinned in some pose); the BVH keeps a float64 copy.
    faces : (m, 3) int
        Triangles, m >= 1; degenerate (zero-area) triangles are allowed and never hit. The BVH keeps
        an int64 copy.

    Attributes
    ----------
    n_faces, n_nodes : int

    Queries take segments a -> b (both (3,) points) and treat the faces as two-sided; they read the
    BVH's copies (``triangle(face)``), never the caller's arrays.
    """

    def __init__(self, positions, faces):
        positions = float_array(positions, "positions", 3, ndim=2)
        faces = index_array(faces, "faces", len(positions))
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise InvalidInputError(f"faces must have shape (m, 3) with m >= 1, got {faces.shape}")
        # copies: positions and faces (48 bytes a face, at most) are what the queries read
        self._build(np.array(positions, np.float64, order="C"), np.array(faces, np.int64, order="C"))

    def _build(self, positions, faces) -> None:
        order = np.arange(len(faces), dtype=np.int32)          # (the build sorts it into leaf order)
        lo, hi, left, right, start, count, n, _ = _build(positions, faces, order, LEAF_SIZE, BOX_PADDING, 0)
        # views of the first n rows: the rows past them (up to 2m - 1) were never written, so never resident
        self._arrays = BVHArrays(lo[:n], hi[:n], left[:n], right[:n], start[:n], count[:n], order, positions,
                                 faces)

    @classmethod
    def of_tree(cls, tree, positions, faces) -> "TriangleBVH":
        """The BVH of the tree fields ``tree`` (``_tree``'s, for example) over checked ``positions`` and
        ``faces`` (as ``of_checked``: kept, not copied)."""
        bvh = cls.__new__(cls)
        bvh._arrays = BVHArrays(*tree, positions, faces)
        return bvh

    @classmethod
    def of_checked(cls, positions, faces) -> "TriangleBVH":
        """The BVH of input already checked: (n, 3) C-contiguous finite float64 positions, (m >= 1, 3)
        C-contiguous int64 faces that index them (a tear stroke builds one per patch, where the checks
        would cost more than the build). It keeps these arrays, not copies: the caller must not change
        them while the BVH is in use."""
        bvh = cls.__new__(cls)
        bvh._build(positions, faces)
        return bvh

    @property
    def n_nodes(self) -> int:
        return len(self._arrays.lo)

    @property
    def n_faces(self) -> int:
        return len(self._arrays.faces)

    def triangle(self, face: int) -> np.ndarray:
        """(3, 3) corners of ``face`` as the BVH holds them (rows: the face's corners in order)."""
        return self._arrays.positions[self._arrays.faces[face]]

    @staticmethod
    def _segment(a, b):
        a = float_array(a, "a", 3, ndim=1)
        b = float_array(b, "b", 3, ndim=1)
        if np.array_equal(a, b):
            raise InvalidInputError(f"the segment has zero length: a = b = {a.tolist()}")
        return a, b

    def first_hit(self, a, b) -> tuple[int, float]:
        """The first crossing of segment a -> b with the surface, going from a towards b.

        Returns (face, t): the face index and the segment parameter t in [0, 1] of the crossing
        point a + t (b - a) (of the faces crossed at the same t, the lowest index); (-1, nan) when the
        segment meets no triangle.
        """
        a, b = self._segment(a, b)
        face, t = _first_hit(tuple(self._arrays), a, b)
        return int(face), float(t)

    def all_hits(self, a, b) -> tuple[np.ndarray, np.ndarray]:
        """Every crossing of segment a -> b: (faces (k,) int64, t (k,) float64), sorted by t."""
        a, b = self._segment(a, b)
        faces, ts = _all_hits(tuple(self._arrays), a, b)
        order = np.argsort(ts, kind="stable")
        return faces[order], ts[order]
