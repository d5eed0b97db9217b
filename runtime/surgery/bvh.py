"""A bounding-volume hierarchy over triangles, for segment queries (the scalpel of ``cgaskin.tear``).

So that a scalpel need not test every face, the faces go into a binary BVH once per set of positions
(rest positions, or the skinned positions of one pose), and each query visits only the boxes that
the segment crosses.

Build: top-down, each node split at the middle of its centroids' extent along the longest axis
(object median when that leaves one side empty), leaves of at most ``LEAF_SIZE`` triangles, in one
numba loop with an explicit stack (``bvh_build.py``). The tree holds face ids in leaf order, not
triangles: a query reads a triangle's corners as positions[faces[face]] (a per-slot copy of the
corners would be the largest array of an editing session's BVH).

Segment–triangle test: the watertight test of Woop, Benthin and Wald, two-sided, through which a
scalpel cannot slip between two faces (``bvh_segment.py``).

A ``TriangleBVH`` keeps copies of its positions and faces; build another when the positions change
(a tear keeps one per rig and pose: ``tear/rig_source.py``; a session updates a ``DynamicBVH``).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._shared.checks import float_array, index_array
from .._shared.jit import F1, F2, I2, f8, kernel, record
from ..errors import InvalidInputError
from ..tolerances import tol
from .bvh_build import N1, _build, _one_leaf
# the queries' tests (``_near_box`` is here for the other queries: tear/locate.py, posed_bounds.py)
from .bvh_segment import _near_box, _push_children, _segment_box, _shear, _watertight  # noqa: F401

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
    """A BVH over the triangles ``faces`` of the mesh at ``positions``: which faces a segment crosses.

    Queries take segments a -> b (both (3,) points) and treat the faces as two-sided; they read the
    BVH's copies (``triangle(face)``), never the caller's arrays.

    Parameters
    ----------
    positions : (n, 3) float
        Vertex positions (rest, or skinned in some pose); the BVH keeps a float64 copy.
    faces : (m, 3) int
        Triangles, m >= 1; degenerate (zero-area) triangles are allowed and never hit. The BVH keeps
        an int64 copy.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> bvh = cgaskin.TriangleBVH(cgaskin.skin(arm, arm.pose("wave", 0.0)), arm.faces)
    >>> bvh.n_faces, bvh.first_hit([1.55, 1, 0.01], [1.55, -1, 0.01])      # down into the arm
    (1376, (704, 0.3759945618368982))
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
        """The BVH of tree fields already built, over checked arrays (kept, not copied).

        Parameters
        ----------
        tree : tuple of 7 arrays
            lo, hi, left, right, start, count, order of ``BVHArrays`` (``_tree``'s, for example).
        positions, faces : (n, 3) float64, (m, 3) int64
            As ``of_checked`` takes them.

        Returns
        -------
        TriangleBVH
        """
        bvh = cls.__new__(cls)
        bvh._arrays = BVHArrays(*tree, positions, faces)
        return bvh

    @classmethod
    def of_checked(cls, positions, faces) -> "TriangleBVH":
        """The BVH of input already checked (a tear's patch: checks would cost more than the build);
        it keeps the arrays, not copies: the caller must not change them while the BVH is in use.

        Parameters
        ----------
        positions : (n, 3) float64
            C-contiguous finite positions.
        faces : (m, 3) int64
            C-contiguous triangles that index them, m >= 1.

        Returns
        -------
        TriangleBVH
        """
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
        """The corners of a face as the BVH holds them, one per row in order.

        Parameters
        ----------
        face : int
            The face's index.

        Returns
        -------
        (3, 3) float64
        """
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

        Parameters
        ----------
        a, b : (3,) float
            The segment's ends (distinct).

        Returns
        -------
        (face, t) : (int, float)
            The face crossed (the lowest index of those crossed at the same t) and the parameter t
            in [0, 1] of the point a + t (b - a); (-1, nan) when the segment meets no face.
        """
        a, b = self._segment(a, b)
        face, t = _first_hit(tuple(self._arrays), a, b)
        return int(face), float(t)

    def all_hits(self, a, b) -> tuple[np.ndarray, np.ndarray]:
        """Every crossing of segment a -> b with the surface, sorted by t.

        Parameters
        ----------
        a, b : (3,) float
            The segment's ends (distinct).

        Returns
        -------
        (faces, t) : ((k,) int64, (k,) float64)
            The faces crossed and the parameters t of the points a + t (b - a), ascending.
        """
        a, b = self._segment(a, b)
        faces, ts = _all_hits(tuple(self._arrays), a, b)
        order = np.argsort(ts, kind="stable")
        return faces[order], ts[order]
