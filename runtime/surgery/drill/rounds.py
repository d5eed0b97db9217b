"""The refinement of a drill's patch (``refine.py`` says what it does) in one compiled call: rounds of
marking the longest edge of every long face the bit's surface crosses, closing the marks and splitting
the faces on them (``bisection.py``), taking in the input faces beyond the patch that share a marked
edge as the closure reaches them.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..._shared.jit import B1, F1, F2, I1, I2, f8, helper, i8, inlined, kernel, record
from .bisection import code_table, longest_edge, midpoints, pair, slot, split
from .bit import signed_distances, surface_crosses
from .patch import LOW_BITS, NEW_POINT, new_rows_and_points

#: how ``refine_rounds`` ended: no face the surface crosses is longer than the step; the rounds ran out
REFINED, OUT_OF_ROUNDS = 0, 1
#: whether a face is to be split (long and crossed)
NO, YES = 0, 1


class InputMesh(NamedTuple):
    """The input mesh as ``refine_rounds`` reads it (it takes ``tuple(InputMesh)``).

    positions : (n, 3) float64 ; faces : (m, 3) int64 ; welded : (n,) int64 the welded vertex of each
    vertex ; welded_faces, face_edges : (m, 3) int64 ; edge_face_offsets : (e + 1,) int64 ;
    edge_face_faces : (3m,) int64 (the ``Topology``'s fields of those names)
    """

    positions: np.ndarray
    faces: np.ndarray
    welded: np.ndarray
    welded_faces: np.ndarray
    face_edges: np.ndarray
    edge_face_offsets: np.ndarray
    edge_face_faces: np.ndarray


class Refined(NamedTuple):
    """The patch ``refine_rounds`` made (it returns the fields as a plain tuple).

    rows : (G, 3) int64 its faces ; sources : (G,) int64 the input face of each
    points : (p, 3) float64 and point_welded : (p,) int64 its points (a midpoint's: ``NEW_POINT``)
    row_points, row_vertex : (r,) int64 its rows' points and input vertices (a midpoint's: -1)
    row_parents : (r, 2) int64 and row_t : (r,) float64 how each row is made (``Patch.new_rows``)
    taken : (k,) int64 the input faces taken in ; status : ``REFINED`` or ``OUT_OF_ROUNDS``
    """

    rows: np.ndarray
    sources: np.ndarray
    points: np.ndarray
    point_welded: np.ndarray
    row_points: np.ndarray
    row_vertex: np.ndarray
    row_parents: np.ndarray
    row_t: np.ndarray
    taken: np.ndarray
    status: int


#: the numba types of ``InputMesh`` and of a patch's maps (row_of (n,), point_of (w,), is_taken (m,))
INPUT_MESH, PATCH_MAPS = record(F2, I2, I1, I2, I2, I1, I1), record(I1, I1, B1)


@kernel((I1, INPUT_MESH, PATCH_MAPS, F1, F1, f8, f8, i8), cost=5.0)
def refine_rounds(first, mesh, maps, start, end, radius, step, rounds):
    """A patch of the input faces ``first`` (k,), refined: ``mesh`` an ``InputMesh``; ``maps`` a new
    patch's row_of, point_of and is_taken, updated in place as faces are taken in.

    Each round marks the longest edge of every face longer than ``step`` that the bit's surface crosses
    (``bit.surface_crosses``), closes the marks (a marked edge marks the longest edge of every face on
    it, found through the faces at each point: ``_corner_lists``), taking in the input faces beyond the
    patch on a marked edge as it goes, and splits the faces on the marks (``bisection.split``); until no
    such face is left, or ``rounds`` ran out. Returns a ``Refined`` as a plain tuple."""
    row_of, point_of, is_taken = maps
    positions, mesh_faces, welded = mesh[0], mesh[1], mesh[2]
    points, point_welded, signed = np.empty((0, 3)), np.empty(0, np.int64), np.empty(0)
    row_point, row_vertex, row_parents, row_t = (np.empty(0, np.int64), np.empty(0, np.int64),
                                                 np.empty((0, 2), np.int64), np.empty(0))
    rows, sources, taken = np.empty((0, 3), np.int64), np.empty(0, np.int64), np.empty(0, np.int64)
    longest, wanted = np.empty(0, np.int64), np.empty(0, np.int8)
    beyond = first
    for _ in range(rounds):
        if beyond.shape[0] == 0 and not (wanted == YES).any():     # (no round left to run)
            return (rows, sources, points, point_welded, row_point, row_vertex, row_parents, row_t, taken, REFINED)
        # the closure of the marks: each marked edge marks the longest edge of every face on it; the
        # input faces beyond the patch on a marked edge join it (a batch at a time), and the closure
        # goes on from them. Marked edges are codes of their points (``pair``), followed in the order marked.
        heads, following = _corner_lists(rows, row_point, points.shape[0], rows.shape[0] + 64)
        marks = code_table(3 * (rows.shape[0] + 64))
        marked = np.empty(3 * (rows.shape[0] + 64), np.int64)
        n_marked = followed = 0
        for f in range(rows.shape[0]):
            if wanted[f] == YES:
                n_marked = _mark(marks, marked, n_marked, _corner_edge(rows, row_point, f, longest[f]))
        pending, n_pending = np.empty(16, np.int64), 0     # input edges with faces beyond the patch
        while followed < n_marked or beyond.shape[0] > 0:
            if beyond.shape[0]:
                is_taken[beyond] = True
                corners = mesh_faces[beyond]
                vertices, vertex_points, point_vertices = new_rows_and_points(
                    corners, welded, row_of, point_of, row_point.shape[0], points.shape[0])
                points = np.concatenate((points, positions[point_vertices]))
                point_welded = np.concatenate((point_welded, welded[point_vertices]))
                signed = np.concatenate((signed, signed_distances(points, signed.shape[0], start, end, radius)))
                row_parents = np.concatenate((row_parents, _itself(row_point.shape[0], vertices.shape[0])))
                row_point = np.concatenate((row_point, vertex_points))
                row_vertex = np.concatenate((row_vertex, vertices))
                row_t = np.concatenate((row_t, np.zeros(vertices.shape[0])))
                first_new = rows.shape[0]
                rows = np.concatenate((rows, _rows_of(corners, row_of)))
                sources = np.concatenate((sources, beyond))
                taken = np.concatenate((taken, beyond))
                more_longest, more_wanted = _describe(rows, first_new, row_point, points, signed, start, end, radius,
                                                      step, np.ones(beyond.shape[0], np.bool_))
                longest = np.concatenate((longest, more_longest))
                wanted = np.concatenate((wanted, more_wanted))
                if first_new == 0 and not (wanted == YES).any():        # (nothing to refine)
                    return (rows, sources, points, point_welded, row_point, row_vertex, row_parents, row_t, taken,
                            REFINED)
                heads, following = _grown(heads, following, points.shape[0], rows.shape[0])
                if 3 * rows.shape[0] > marked.shape[0]:
                    marked = np.concatenate((marked, np.empty(3 * rows.shape[0], np.int64)))
                    marks = _rehashed(marks, marked, n_marked, 3 * rows.shape[0])
                for g in range(first_new, rows.shape[0]):
                    _add_corners(heads, following, rows, row_point, g)
                # each is on a marked edge (it marks its longest), or one of the first (then if wanted)
                for g in range(first_new, rows.shape[0]):
                    if first_new > 0 or wanted[g] == YES:
                        n_marked = _mark(marks, marked, n_marked, _corner_edge(rows, row_point, g, longest[g]))
                beyond = np.empty(0, np.int64)
                continue
            code = marked[followed]
            followed += 1
            a, b = code >> 32, code & LOW_BITS
            edge = _open_input_edge(heads, following, rows, row_point, a, b, sources, point_welded, mesh, is_taken)
            if edge >= 0:
                if n_pending == pending.shape[0]:
                    pending = np.concatenate((pending, np.empty(n_pending, np.int64)))
                pending[n_pending] = edge
                n_pending += 1
            corner = heads[a]
            while corner >= 0:
                g, k = corner // 3, _edge_at(rows, row_point, corner, b)
                if k >= 0:
                    n_marked = _mark(marks, marked, n_marked, _corner_edge(rows, row_point, g, longest[g]))
                corner = following[corner]
            if followed == n_marked and n_pending:
                beyond, n_pending = _faces_on(pending[:n_pending], mesh, is_taken), 0
        if n_marked == 0:
            return (rows, sources, points, point_welded, row_point, row_vertex, row_parents, row_t, taken, REFINED)
        on_marked = np.zeros(rows.shape, np.bool_)
        for i in range(n_marked):
            a, b = marked[i] >> 32, marked[i] & LOW_BITS
            corner = heads[a]
            while corner >= 0:
                k = _edge_at(rows, row_point, corner, b)
                if k >= 0:
                    on_marked[corner // 3, k] = True
                corner = following[corner]
        rows, made_from, kept, parents, points_of_rows, point_parents = split(
            rows, row_point, points, on_marked, row_point.shape[0], points.shape[0])
        sources = sources[made_from]
        points = np.concatenate((points, midpoints(points, point_parents)))
        point_welded = np.concatenate((point_welded, np.full(point_parents.shape[0], NEW_POINT, np.int64)))
        signed = np.concatenate((signed, signed_distances(points, signed.shape[0], start, end, radius)))
        row_point = np.concatenate((row_point, points_of_rows))
        row_vertex = np.concatenate((row_vertex, np.full(parents.shape[0], -1, np.int64)))
        row_parents = np.concatenate((row_parents, parents))
        row_t = np.concatenate((row_t, np.full(parents.shape[0], 0.5)))
        # the faces not split keep what was found about them; the halves of a face to be split are
        # asked (a part of one that was not is not either: shorter, on the same side of the surface)
        half_longest, half_wanted = _describe(rows, kept, row_point, points, signed, start, end, radius, step,
                                              wanted[made_from[kept:]] == YES)
        longest = np.concatenate((longest[made_from[:kept]], half_longest))
        wanted = np.concatenate((wanted[made_from[:kept]], half_wanted))
    return (rows, sources, points, point_welded, row_point, row_vertex, row_parents, row_t, taken, OUT_OF_ROUNDS)


@helper
def _corner_lists(rows, row_point, n_points, capacity):
    """The faces at each point, as lists of corners (corner 3 f + k: corner k of face f): heads (n_points,)
    the last corner at each point (-1: none), following (3 capacity,) the corner before each at its point;
    for the faces ``rows`` (F, 3) (``row_point`` (R,) their rows' points), with room for ``capacity``
    faces (``_add_corners`` adds more)."""
    heads, following = np.full(n_points, -1, np.int64), np.empty(3 * capacity, np.int64)
    for f in range(rows.shape[0]):
        _add_corners(heads, following, rows, row_point, f)
    return heads, following


@inlined
def _add_corners(heads, following, rows, row_point, f):
    """Add face f's corners to ``_corner_lists``."""
    for k in range(3):
        p = row_point[rows[f, k]]
        following[3 * f + k] = heads[p]
        heads[p] = 3 * f + k


@helper
def _grown(heads, following, n_points, n_faces):
    """``_corner_lists`` with room for ``n_points`` points and ``n_faces`` faces (the same lists)."""
    if heads.shape[0] < n_points:
        heads = np.concatenate((heads, np.full(n_points - heads.shape[0], -1, np.int64)))
    if following.shape[0] < 3 * n_faces:
        following = np.concatenate((following, np.empty(3 * n_faces, np.int64)))
    return heads, following


@inlined
def _edge_at(rows, row_point, corner, b):
    """Which corner edge (k -> k + 1) of the face of ``corner`` (3 f + k, at point a) joins a to point b:
    k, or the edge before it (b -> a), or -1 where b is not a corner of the face."""
    f, k = corner // 3, corner % 3
    if row_point[rows[f, (k + 1) % 3]] == b:
        return k
    if row_point[rows[f, (k + 2) % 3]] == b:
        return (k + 2) % 3
    return -1


@inlined
def _corner_edge(rows, row_point, f, k):
    """The code (``pair``) of the points of face f's corner edge k -> k + 1."""
    return pair(row_point[rows[f, k]], row_point[rows[f, (k + 1) % 3]])


@inlined
def _mark(marks, marked, n_marked, code):
    """Mark the edge of ``code`` (once: in the table ``marks`` and appended to ``marked``, to be followed);
    the number marked."""
    at = slot(marks, code)
    if marks[at] != code:
        marks[at] = code
        marked[n_marked] = code
        n_marked += 1
    return n_marked


@helper
def _rehashed(marks, marked, n_marked, count):
    """A ``code_table`` for ``count`` codes holding the first ``n_marked`` of ``marked``."""
    if marks.shape[0] >= 2 * count + 2:
        return marks
    table = code_table(count)
    for i in range(n_marked):
        table[slot(table, marked[i])] = marked[i]
    return table


@helper
def _describe(rows, first, row_point, points, signed, start, end, radius, step, ask):
    """For the faces of ``rows`` from ``first`` on: the corner (k,) whose edge is longest, and whether
    each is to be split (k,) int8: longer than ``step`` and crossed by the bit's surface
    (``bit.surface_crosses``; ``signed`` (P,) the points' signed distances), asked where ``ask`` (k,)
    (elsewhere not)."""
    k = rows.shape[0] - first
    longest, wanted, x = np.empty(k, np.int64), np.zeros(k, np.int8), np.empty(3)
    for i in range(k):
        f = first + i
        p, q, r = row_point[rows[f, 0]], row_point[rows[f, 1]], row_point[rows[f, 2]]
        longest[i], squared = longest_edge(points, p, q, r)
        if ask[i] and squared > step * step and surface_crosses(points, p, q, r, signed, math.sqrt(squared), start,
                                                                end, radius, x):
            wanted[i] = YES
    return longest, wanted


@inlined
def _open_input_edge(heads, following, rows, row_point, a, b, sources, point_welded, mesh, is_taken):
    """The input edge (its id in ``mesh``) that the patch's edge between points a and b is, if input faces
    not ``taken`` have it too; else -1. (An edge between two input points is an edge of the input face
    it lies in: bisection joins a new point to a corner; ``sources`` (F,) the patch faces' input faces,
    ``heads``, ``following`` their ``_corner_lists``.)"""
    wa, wb = point_welded[a], point_welded[b]
    if wa == NEW_POINT or wb == NEW_POINT:
        return -1
    welded_faces, face_edges, offsets, edge_faces = mesh[3], mesh[4], mesh[5], mesh[6]
    corner = heads[a]
    while corner >= 0:
        s = sources[corner // 3]
        if s >= 0 and _edge_at(rows, row_point, corner, b) >= 0:
            for j in range(3):
                u, v = welded_faces[s, j], welded_faces[s, (j + 1) % 3]
                if (u == wa and v == wb) or (u == wb and v == wa):
                    edge = face_edges[s, j]
                    for i in range(offsets[edge], offsets[edge + 1]):
                        if not is_taken[edge_faces[i]]:
                            return edge
                    return -1
        corner = following[corner]
    return -1
@helper
def _faces_on(edges, mesh, is_taken):
    """The distinct input faces (k,) not ``taken`` on the input ``edges`` (e,) (ids in ``mesh``)."""
    offsets, edge_faces = mesh[5], mesh[6]
    total = 0
    for edge in edges:
        total += offsets[edge + 1] - offsets[edge]
    out, count = np.empty(total, np.int64), 0
    for edge in edges:
        for i in range(offsets[edge], offsets[edge + 1]):
            g = edge_faces[i]
            if is_taken[g]:
                continue
            seen = False
            for j in range(count):
                seen |= out[j] == g
            if not seen:
                out[count] = g
                count += 1
    return out[:count].copy()


@helper
def _rows_of(corners, row_of):
    """(k, 3) the rows of the input vertices ``corners`` (k, 3)."""
    out = np.empty(corners.shape, np.int64)
    for i in range(corners.shape[0]):
        for k in range(3):
            out[i, k] = row_of[corners[i, k]]
    return out


@helper
def _itself(first, count):
    """(count, 2): rows first, first + 1, ... each as its own parents (an input row)."""
    out = np.empty((count, 2), np.int64)
    for i in range(count):
        out[i, 0] = out[i, 1] = first + i
    return out
