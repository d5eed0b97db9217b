"""The faces around a drill's rim, refined until the rim can be drawn finely: longest-edge bisection.

A hole is round only if the mesh has vertices close together where the bit's surface crosses it; a real
model's faces are often larger than the hole. So before the rim is placed, every face that the bit's
surface passes through (part of it inside the bit, part outside: ``bit.near_faces``) and whose longest
edge is longer than ``step`` is bisected on its longest edge, and a face that shares a bisected edge is
bisected too (on its longest edge first, then on the shared one: Rivara's longest-edge bisection, which
keeps the angles of the refined faces bounded and leaves no vertex in the middle of a neighbour's edge). Rounds repeat until
no face the surface passes through is longer than ``step``: the rim's edges are then at most ``step``
long, and a face left outside the bit reaches into it by no more than such an edge's sagitta.

The faces are the patch's (``patch.py``); edges are marked by their welded points, so that the
bisection of a seam edge is seen from both sides.
"""
from __future__ import annotations

import numpy as np

from ...errors import InternalError
from .bit import near_faces
from .patch import Patch

#: refinement rounds before giving up (each halves the faces near the rim: 2^60 is beyond any model)
MAX_ROUNDS = 60


def _edge_codes(face_points) -> np.ndarray:
    """(F, 3) int64: each corner edge k -> k+1 of the faces (F, 3) of point ids, as one integer (the lower
    id in the high 32 bits)."""
    a, b = face_points, np.roll(face_points, -1, axis=1)
    return (np.minimum(a, b) << 32) | np.maximum(a, b)


def _edge_pairs(codes) -> set:
    """The (lower, higher) point-id pairs of edge codes."""
    return set(zip((codes >> 32).tolist(), (codes & 0xFFFFFFFF).tolist()))


def _longest(points, face_points) -> tuple:
    """(F,) the corner k whose edge k -> k+1 is longest in each face (the first on a tie), (F,) its
    squared length."""
    d = points[np.roll(face_points, -1, axis=1)] - points[face_points]
    squared = np.einsum("fkc,fkc->fk", d, d)
    k = np.argmax(squared, axis=1)
    return k, squared[np.arange(len(k)), k]


def refine(patch: Patch, bit, step: float) -> None:
    """Bisect the patch's faces that the bit's surface passes through until none is longer than ``step``
    (module docstring), taking in the input faces beyond the patch that share a bisected edge."""
    start, end, radius = bit
    for _ in range(MAX_ROUNDS):
        points, face_points = patch.point_array(), patch.face_points()
        low, high = near_faces(points, face_points, start, end, radius)
        k, squared = _longest(points, face_points)
        chosen = np.flatnonzero((low < 0.0) & (high > 0.0) & (squared > step * step))    # the bit's surface meets it
        if not len(chosen):
            return
        marked = _close(patch, np.unique(_edge_codes(face_points)[chosen, k[chosen]]))
        bisect_marked(patch, marked)
    raise InternalError(f"the faces near the bit did not become shorter than {step:g} in {MAX_ROUNDS} rounds")


def _close(patch: Patch, marked) -> np.ndarray:
    """The edge codes ``marked`` and the longest edge of every face that has a marked edge, until none
    is added; input faces beyond the patch on a marked input edge join it first."""
    topology, welded = patch.topology, patch.point_welded
    seen = set()
    codes = None
    while True:
        grown = False
        for a, b in _edge_pairs(marked):
            if (a, b) in seen:
                continue
            seen.add((a, b))
            if a in welded and b in welded:
                for face in _input_faces(topology, welded[a], welded[b]):
                    grown |= patch.take(int(face))
        if grown or codes is None:          # (the faces' edges and longest edges, again when faces came in)
            points, face_points = patch.point_array(), patch.face_points()
            codes = _edge_codes(face_points)
            k, _ = _longest(points, face_points)
        has = np.isin(codes, marked).any(axis=1)
        added = np.setdiff1d(codes[has, k[has]], marked)
        if not len(added) and not grown:
            return marked
        marked = np.union1d(marked, added)


def _input_faces(topology, wa: int, wb: int) -> np.ndarray:
    """The input faces on welded edge wa-wb (empty when it is not an input edge)."""
    lo, hi = min(wa, wb), max(wa, wb)
    edges = topology.edges
    first, last = np.searchsorted(edges[:, 0], lo, "left"), np.searchsorted(edges[:, 0], lo, "right")
    for e in range(first, last):
        if edges[e, 1] == hi:
            offsets = topology.edge_face_offsets
            return topology.edge_face_faces[offsets[e]:offsets[e + 1]]
    return np.empty(0, np.int64)


def bisect_marked(patch: Patch, marked, place=None) -> None:
    """Split every face with marked edges (codes): on its longest edge where it is marked (``_close``
    sees to it), then each half on the marked edge it keeps; ``place`` as for ``Patch.midpoint_row``.
    The faces split go, their halves come after the others."""
    points, face_points = patch.point_array(), patch.face_points()
    k, _ = _longest(points, face_points)
    split = np.isin(_edge_codes(face_points), marked)
    pairs = _edge_pairs(marked)
    splitting = split.any(axis=1)
    faces = [rows for rows, s in zip(patch.faces, splitting.tolist()) if not s]
    sources = [source for source, s in zip(patch.face_source, splitting.tolist()) if not s]
    for f in np.flatnonzero(splitting).tolist():
        children = _split(patch, patch.faces[f], int(k[f]), split[f].tolist(), pairs, place)
        faces.extend(children)
        sources.extend([patch.face_source[f]] * len(children))
    patch.faces, patch.face_source = faces, sources


def _split(patch: Patch, rows, longest: int, marks: list, pairs: set, place=None) -> list:
    """The faces that replace ``rows`` (3 rows, wound as the input face) when its marked edges (``marks``
    per corner edge; ``pairs`` every marked point pair) are bisected: 2 to 4 faces, wound as the face."""
    k = longest if marks[longest] else marks.index(True)
    a, b, c = rows[k], rows[(k + 1) % 3], rows[(k + 2) % 3]
    m = patch.midpoint_row(a, b, place)
    # each half keeps one of the face's other two edges (c-a, b-c): bisected too where it is marked
    if patch.point_edge(c, a) in pairs:
        n = patch.midpoint_row(c, a, place)
        out = [[a, m, n], [m, c, n]]
    else:
        out = [[a, m, c]]
    if patch.point_edge(b, c) in pairs:
        n = patch.midpoint_row(b, c, place)
        out += [[m, b, n], [m, n, c]]
    else:
        out.append([m, b, c])
    return out
