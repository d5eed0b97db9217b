"""The faces around a drill's rim, refined until the rim can be drawn finely: longest-edge bisection.

A hole is round only if the mesh has vertices close together where the bit's surface crosses it; a real
model's faces are often larger than the hole. So before the rim is placed, every face that the bit's
surface passes through (part of it inside the bit, part outside: ``bit.crossed_faces``) and whose longest
edge is longer than ``step`` is bisected on its longest edge, and a face that shares a bisected edge is
bisected too (on its longest edge first, then on the shared one: Rivara's longest-edge bisection, which
keeps the angles of the refined faces bounded and leaves no vertex in the middle of a neighbour's edge).
Rounds repeat until no face the surface passes through is longer than ``step``: the rim's edges are then
at most ``step`` long, and a face left outside the bit reaches into it by no more than such an edge's sagitta.

The faces are the patch's (``patch.py``); edges are marked by their welded points, so that the
bisection of a seam edge is seen from both sides. Each round works on whole arrays: the faces near the
surface, the closure of the marked edges and the faces' halves (``bisection.py``).
"""
from __future__ import annotations

import numpy as np

from ..._shared.ids import distinct
from ...errors import InternalError
from .bit import crossed_faces
from .bisection import closure, longest_edges, split_marked
from .patch import Patch, edge_codes, pair_codes

#: refinement rounds before giving up (each halves the faces near the rim: 2^60 is beyond any model)
MAX_ROUNDS = 60


def refine(patch: Patch, bit, step: float) -> None:
    """Bisect the patch's faces that the bit's surface passes through until none is longer than ``step``
    (module docstring), taking in the input faces beyond the patch that share a bisected edge."""
    start, end, radius = bit
    border = None                       # (made when a closure first needs it)
    for _ in range(MAX_ROUNDS):
        points, face_points = patch.point_array(), patch.face_points()
        k, squared = longest_edges(points, face_points)
        long = np.flatnonzero(squared > step * step)
        chosen = long[crossed_faces(points, face_points[long], start, end, radius)]
        if not len(chosen):
            return
        codes = edge_codes(face_points)
        longest = codes[np.arange(len(k)), k]
        marked, border = _close(patch, longest[chosen], codes, longest, border)
        bisect_marked(patch, marked)
    raise InternalError(f"the faces near the bit did not become shorter than {step:g} in {MAX_ROUNDS} rounds")


def _close(patch: Patch, marked, codes, longest, border) -> tuple:
    """(the sorted edge codes ``marked`` and the longest edge of every face that has a marked edge,
    until none is added (``bisection.closure``); the patch's border). ``codes`` (F, 3) are the faces'
    edges, ``longest`` (F,) the longest of each; where a marked edge is an edge of the ``border``
    (``_border``; None: not made yet), the input faces beyond the whole border join the patch first (a
    ring at a time: the closure, having crossed once, usually crosses again nearby)."""
    border = _border(patch) if border is None else border
    while True:
        marked = np.sort(closure(codes, longest, marked))
        if not _in_sorted(marked, border[0]).any():
            return marked, border
        before = len(patch.faces)
        patch.take(_faces_on(patch.topology, border[1]))
        face_points = patch.face_points()[before:]          # (the faces taken come last)
        k, _ = longest_edges(patch.point_array(), face_points)
        taken_codes = edge_codes(face_points)
        codes = np.concatenate([codes, taken_codes])
        longest = np.concatenate([longest, taken_codes[np.arange(len(k)), k]])
        border = _border(patch)


def _border(patch: Patch) -> tuple:
    """The taken faces' input edges that faces not taken share too: (sorted codes (b,) of their point
    pairs, their ids (b,) in the input's topology)."""
    topology, taken = patch.topology, patch.taken
    edges, counts = np.unique(topology.face_edges[taken], return_counts=True)
    offsets = topology.edge_face_offsets
    open_edges = edges[counts < offsets[edges + 1] - offsets[edges]]
    points = patch.point_of[topology.edges[open_edges]]
    codes = pair_codes(points[:, 0], points[:, 1])
    order = np.argsort(codes)
    return codes[order], open_edges[order]


def _faces_on(topology, edges) -> np.ndarray:
    """The distinct input faces (k,) on the input edges ``edges`` (e,) (ids in ``topology``)."""
    offsets = topology.edge_face_offsets
    starts, counts = offsets[edges], offsets[edges + 1] - offsets[edges]
    runs = np.repeat(starts - (np.cumsum(counts) - counts), counts)       # (each edge's run of incidences)
    return distinct(topology.edge_face_faces[runs + np.arange(counts.sum())])


def bisect_marked(patch: Patch, marked, place=None) -> None:
    """Split every face with marked edges (codes of point pairs): on its longest edge where it is marked
    (``_close`` sees to it), then each half on the marked edge it keeps (``bisection.split_marked``).
    Each marked edge gets one new point, at its midpoint or, when given, where ``place(a (k,), b (k,))
    -> (k, 3)`` says for the edges between points a and b (called just before the k points are added);
    each vertex edge on it gets one new row (a seam's copies share the point). The faces split go, their
    halves come after the others."""
    faces, made_from, row_parents, row_points, point_parents = split_marked(
        patch.faces, patch.row_point, patch.point_array(), marked, patch.n_rows, patch.n_points)
    a, b = point_parents[:, 0], point_parents[:, 1]
    points = patch.point_array()
    patch.add_points(0.5 * (points[a] + points[b]) if place is None else place(a, b))
    patch.new_rows(row_points, row_parents[:, 0], row_parents[:, 1], 0.5)
    patch.replace_faces(faces, patch.face_source[made_from])


def _in_sorted(values, sorted_values) -> np.ndarray:
    """(same shape as ``values``) whether each value is one of ``sorted_values`` (k,) (ascending)."""
    if not len(sorted_values):
        return np.zeros(values.shape, bool)
    at = np.minimum(np.searchsorted(sorted_values, values), len(sorted_values) - 1)
    return sorted_values[at] == values
