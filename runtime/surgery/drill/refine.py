"""The faces around a drill's rim, refined until the rim can be drawn finely: longest-edge bisection.

A hole is round only if the mesh has vertices close together where the bit's surface crosses it; a real
model's faces are often larger than the hole. So before the rim is placed, every face that the bit's
surface passes through (part of it inside the bit, part outside: ``bit.near_faces``) and whose longest
edge is longer than ``step`` is bisected on its longest edge, and a face that shares a bisected edge is
bisected too (on its longest edge first, then on the shared one: Rivara's longest-edge bisection, which
keeps the angles of the refined faces bounded and leaves no vertex in the middle of a neighbour's edge).
Rounds repeat until no face the surface passes through is longer than ``step``: the rim's edges are then
at most ``step`` long, and a face left outside the bit reaches into it by no more than such an edge's sagitta.

The faces are the patch's (``patch.py``); edges are marked by their welded points, so that the
bisection of a seam edge is seen from both sides. Each round works on whole arrays: the faces near the
surface, the closure of the marked edges (``_closure_step``) and the faces' children (``_children``).
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F2, I1, I2, helper, kernel
from ...errors import InternalError
from .bit import near_faces
from .patch import LOW_BITS, Patch, edge_codes, pair_codes, put_face

#: refinement rounds before giving up (each halves the faces near the rim: 2^60 is beyond any model)
MAX_ROUNDS = 60


def refine(patch: Patch, bit, step: float) -> None:
    """Bisect the patch's faces that the bit's surface passes through until none is longer than ``step``
    (module docstring), taking in the input faces beyond the patch that share a bisected edge."""
    start, end, radius = bit
    border = None                       # (made when a closure first needs it)
    for _ in range(MAX_ROUNDS):
        points, face_points = patch.point_array(), patch.face_points()
        k, squared = _longest(points, face_points)
        long = np.flatnonzero(squared > step * step)
        low, high = near_faces(points, face_points[long], start, end, radius)
        chosen = long[(low < 0.0) & (high > 0.0)]           # the bit's surface passes through them
        if not len(chosen):
            return
        codes = edge_codes(face_points)
        longest = codes[np.arange(len(k)), k]
        marked, border = _close(patch, np.unique(longest[chosen]), codes, longest, border)
        bisect_marked(patch, marked)
    raise InternalError(f"the faces near the bit did not become shorter than {step:g} in {MAX_ROUNDS} rounds")


def _close(patch: Patch, marked, codes, longest, border) -> tuple:
    """(the edge codes ``marked`` and the longest edge of every face that has a marked edge, until none
    is added; the patch's border edges). ``codes`` (F, 3) are the faces' edges, ``longest`` (F,) the
    longest of each; where a marked edge is a ``border`` edge (``_border_edges``; None: not made yet),
    the input faces beyond it join the patch first."""
    border = _border_edges(patch) if border is None else border
    while True:
        added = _closure_step(codes, longest, marked)
        while len(added):
            marked = np.union1d(marked, added)
            added = _closure_step(codes, longest, marked)
        across = marked[_in_sorted(marked, border)]
        if not len(across):
            return marked, border
        before = len(patch.faces)
        patch.take(np.unique(np.concatenate([_input_faces(patch, code) for code in across.tolist()])))
        face_points = patch.face_points()[before:]          # (the faces taken come last)
        k, _ = _longest(patch.point_array(), face_points)
        taken_codes = edge_codes(face_points)
        codes = np.concatenate([codes, taken_codes])
        longest = np.concatenate([longest, taken_codes[np.arange(len(k)), k]])
        border = _border_edges(patch)


def _border_edges(patch: Patch) -> np.ndarray:
    """Sorted codes (point pairs) of the taken faces' input edges that faces not taken share too."""
    topology, taken = patch.topology, patch.taken
    edges, counts = np.unique(topology.face_edges[taken], return_counts=True)
    offsets = topology.edge_face_offsets
    open_edges = edges[counts < offsets[edges + 1] - offsets[edges]]
    points = patch.point_of[topology.edges[open_edges]]
    return np.unique(pair_codes(points[:, 0], points[:, 1]))


def _input_faces(patch: Patch, code: int) -> np.ndarray:
    """The input faces on the input edge between the points of ``code``."""
    wa, wb = patch.point_welded[[code >> 32, code & LOW_BITS]].tolist()
    lo, hi = min(wa, wb), max(wa, wb)
    topology = patch.topology
    edges = topology.edges
    first, last = np.searchsorted(edges[:, 0], lo, "left"), np.searchsorted(edges[:, 0], lo, "right")
    e = first + int(np.flatnonzero(edges[first:last, 1] == hi)[0])
    offsets = topology.edge_face_offsets
    return topology.edge_face_faces[offsets[e]:offsets[e + 1]]


def bisect_marked(patch: Patch, marked, place=None) -> None:
    """Split every face with marked edges (sorted codes of point pairs): on its longest edge where it is
    marked (``_close`` sees to it), then each half on the marked edge it keeps. Each marked edge gets one
    new point, at its midpoint or, when given, where ``place(a (k,), b (k,)) -> (k, 3)`` says for the
    edges between points a and b (called just before the k points are added); each vertex edge on it
    gets one new row (a seam's copies share the point). The faces split go, their halves come after the
    others."""
    rows, sources = patch.faces, patch.face_source
    face_points = patch.row_point[rows]
    k, _ = _longest(patch.point_array(), face_points)
    split = _in_sorted(edge_codes(face_points), marked)
    splitting = split.any(axis=1)
    row_edges, row_edge_of = np.unique(edge_codes(rows)[split], return_inverse=True)
    row_a, row_b = row_edges >> 32, row_edges & LOW_BITS
    point_edges, point_edge_of = np.unique(pair_codes(patch.row_point[row_a], patch.row_point[row_b]),
                                           return_inverse=True)
    a, b = point_edges >> 32, point_edges & LOW_BITS
    points = patch.point_array()
    first_point = patch.add_points(0.5 * (points[a] + points[b]) if place is None else place(a, b))
    first_row = patch.new_rows(first_point + point_edge_of, row_a, row_b, 0.5)
    midpoint = np.full(rows.shape, -1, np.int64)
    midpoint[split] = first_row + row_edge_of
    children, parent = _children(rows[splitting], midpoint[splitting], k[splitting])
    patch.replace_faces(np.concatenate([rows[~splitting], children]),
                        np.concatenate([sources[~splitting], sources[splitting][parent]]))


@kernel((F2, I2), cost=0.2)
def _longest(points, face_points):
    """(F,) the corner k whose edge k -> k+1 is longest in each face (F, 3) of ``points`` (P, 3) (the
    first on a tie), (F,) its squared length."""
    n = face_points.shape[0]
    longest, squared = np.zeros(n, np.int64), np.full(n, -1.0)
    for f in range(n):
        for k in range(3):
            a, b = face_points[f, k], face_points[f, (k + 1) % 3]
            d = (points[b, 0] - points[a, 0]) ** 2 + (points[b, 1] - points[a, 1]) ** 2 \
                + (points[b, 2] - points[a, 2]) ** 2
            if d > squared[f]:
                longest[f], squared[f] = k, d
    return longest, squared


def _in_sorted(values, sorted_values) -> np.ndarray:
    """(same shape as ``values``) whether each value is one of ``sorted_values`` (k,) (ascending)."""
    if not len(sorted_values):
        return np.zeros(values.shape, bool)
    at = np.minimum(np.searchsorted(sorted_values, values), len(sorted_values) - 1)
    return sorted_values[at] == values


@kernel((I2, I1, I1), cost=0.2)
def _closure_step(codes, longest, marked):
    """The longest edges ``longest[f]`` (F,) not among the sorted edge codes ``marked`` (k,) of the faces
    f with a marked edge among ``codes[f]`` (F, 3) (with repeats): what the closure adds next."""
    added = np.empty(codes.shape[0], np.int64)
    count = 0
    for f in range(codes.shape[0]):
        if _holds(marked, longest[f]):
            continue
        for k in range(3):
            if _holds(marked, codes[f, k]):
                added[count] = longest[f]
                count += 1
                break
    return added[:count].copy()


@helper
def _holds(sorted_codes, code):
    """Whether ``code`` is one of ``sorted_codes`` (ascending): a binary search."""
    lo, hi = 0, sorted_codes.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if sorted_codes[mid] < code:
            lo = mid + 1
        else:
            hi = mid
    return lo < sorted_codes.shape[0] and sorted_codes[lo] == code


@kernel((I2, I2, I1), cost=0.3)
def _children(rows, midpoint, longest):
    """The faces that replace faces ``rows`` (F, 3) whose corner edges k -> k+1 with ``midpoint[f, k]``
    >= 0 (F, 3) are bisected at that row: on the longest edge ``longest[f]`` (F,) if it is bisected
    (else the first that is), then each half on the other edge it keeps, if that is bisected: 2 to 4
    faces, wound as the face. Returns faces (C, 3) and the face (C,) each replaces."""
    n = rows.shape[0]
    out, parent = np.empty((4 * n, 3), np.int64), np.empty(4 * n, np.int64)
    count = 0
    for f in range(n):
        k = longest[f]
        if midpoint[f, k] < 0:
            k = 0
            while midpoint[f, k] < 0:
                k += 1
        a, b, c = rows[f, k], rows[f, (k + 1) % 3], rows[f, (k + 2) % 3]
        m, on_ca, on_bc = midpoint[f, k], midpoint[f, (k + 2) % 3], midpoint[f, (k + 1) % 3]
        # each half keeps one of the face's other two edges (c-a, b-c): bisected too where it is marked
        if on_ca >= 0:
            count = put_face(out, parent, count, f, a, m, on_ca)
            count = put_face(out, parent, count, f, m, c, on_ca)
        else:
            count = put_face(out, parent, count, f, a, m, c)
        if on_bc >= 0:
            count = put_face(out, parent, count, f, m, b, on_bc)
            count = put_face(out, parent, count, f, m, on_bc, c)
        else:
            count = put_face(out, parent, count, f, m, b, c)
    return out[:count].copy(), parent[:count].copy()

