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
from .bisection import EMPTY, add_face_edges, code_table, edge_map, grown, halves, longest_edge, pair, \
    remove_face_edges, slot, with_room
from .bit import _signed_distances, surface_crosses
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
#: the entries of ``refine_rounds``' ``sizes``: the faces, points, rows and input faces taken in so far
FACES, POINTS, ROWS, TAKEN = 0, 1, 2, 3

# Inside ``refine_rounds`` the patch lives in arrays with room to grow (``bisection.grown``), the first
# ``sizes[...]`` rows of each in use, grouped as plain tuples:
#   faces: (rows (F, 3), sources (F,), codes (F, 3) the edges' codes, longest (F,) the corner of the
#          longest edge, wanted (F,) int8 whether the face is to be split: ``_describe``)
#   points: (positions (P, 3), welded (P,) the input's welded vertex or NEW_POINT, signed (P,) f)
#   made: (point (R,), vertex (R,) the input vertex or -1, parents (R, 2), t (R,)) of each row
#   marks: (marked (E,) per edge of the ``edge_map``, stack (E,) the marked edges still to follow)


@kernel((I1, INPUT_MESH, PATCH_MAPS, F1, F1, f8, f8, i8), cost=2.0)
def refine_rounds(first, mesh, maps, start, end, radius, step, rounds):
    """A patch of the input faces ``first`` (k,), refined: ``mesh`` an ``InputMesh``; ``maps`` a new
    patch's row_of, point_of and is_taken, updated in place as faces are taken in.

    Each round marks the longest edge of every face longer than ``step`` that the bit's surface crosses
    (``bit.surface_crosses``), closes the marks (a marked edge marks the longest edge of every face on
    it, through an ``edge_map`` kept from round to round), taking in the input faces beyond the patch
    on a marked edge as it goes (``_take_in``), and splits the faces on the marks where they are
    (``_split``); until no such face is left, or ``rounds`` ran out. Returns a ``Refined`` as a plain
    tuple."""
    capacity = 4 * first.shape[0] + 64
    sizes = np.zeros(4, np.int64)
    faces = (np.empty((capacity, 3), np.int64), np.empty(capacity, np.int64), np.empty((capacity, 3), np.int64),
             np.empty(capacity, np.int64), np.empty(capacity, np.int8))
    points = (np.empty((capacity, 3)), np.empty(capacity, np.int64), np.empty(capacity))
    made = (np.empty(capacity, np.int64), np.empty(capacity, np.int64), np.empty((capacity, 2), np.int64),
            np.empty(capacity))
    emap = edge_map(faces[2], 0, capacity)
    marks = (np.zeros(emap[2].shape[0], np.bool_), np.empty(emap[2].shape[0], np.int64))
    faces, points, made, taken, emap, marks = _take_in(first, faces, points, made, np.empty(16, np.int64), sizes,
                                                       emap, marks, mesh, maps, start, end, radius, step)
    for _ in range(rounds):
        marked, stack = marks
        depth = 0
        for f in range(sizes[FACES]):
            if faces[4][f] == YES:
                depth = _mark(marked, stack, depth, emap[5][f, faces[3][f]])
        if depth == 0:
            return _refined(faces, points, made, taken, sizes, REFINED)
        # the closure: each marked edge marks the longest edge of every face on it; the input faces
        # beyond the patch on a marked edge join it (a batch at a time), and the closure
        pending, n_pending = np.empty(16, np.int64), 0
        followed, n_followed = np.empty(16, np.int64), 0
        while depth > 0 or n_pending > 0:
            if depth == 0:
                beyond = _faces_on(pending[:n_pending], mesh, maps[2])
                n_pending = 0
                faces, points, made, taken, emap, marks = _take_in(beyond, faces, points, made, taken, sizes, emap,
                                                                   marks, mesh, maps, start, end, radius, step)
                marked, stack = marks
                for g in range(sizes[FACES] - beyond.shape[0], sizes[FACES]):      # (each is on a marked edge)
                    depth = _mark(marked, stack, depth, emap[5][g, faces[3][g]])
                continue
            depth -= 1
            e = stack[depth]
            followed = grown(followed, n_followed + 1)
            followed[n_followed] = e
            n_followed += 1
            edge = _open_input_edge(emap, e, faces[1], points[1], mesh, maps[2])
            if edge >= 0:
                pending = grown(pending, n_pending + 1)
                pending[n_pending] = edge
                n_pending += 1
            incidence = emap[3][e]
            while incidence >= 0:
                g = incidence // 3
                depth = _mark(marked, stack, depth, emap[5][g, faces[3][g]])
                incidence = emap[4][incidence]
        faces, points, made, emap, marks = _split(followed[:n_followed], faces, points, made, sizes, emap, marks,
                                                  start, end, radius, step)
    return _refined(faces, points, made, taken, sizes, OUT_OF_ROUNDS)


@helper
def _refined(faces, points, made, taken, sizes, status):
    """``refine_rounds``' result: the records' rows in use."""
    n, n_points, n_rows = sizes[FACES], sizes[POINTS], sizes[ROWS]
    return (faces[0][:n].copy(), faces[1][:n].copy(), points[0][:n_points].copy(), points[1][:n_points].copy(),
            made[0][:n_rows].copy(), made[1][:n_rows].copy(), made[2][:n_rows].copy(), made[3][:n_rows].copy(),
            taken[:sizes[TAKEN]].copy(), status)


@helper
def _take_in(beyond, faces, points, made, taken, sizes, emap, marks, mesh, maps, start, end, radius, step):
    """Add the input faces ``beyond`` (k,) to the patch (``maps`` updated), with rows for their vertices
    that have none and points for their welded vertices that have none; returns the grown records."""
    positions, mesh_faces, welded = mesh[0], mesh[1], mesh[2]
    row_of, point_of, is_taken = maps
    n, n_points, n_rows, k = sizes[FACES], sizes[POINTS], sizes[ROWS], beyond.shape[0]
    is_taken[beyond] = True
    taken = grown(taken, sizes[TAKEN] + k)
    taken[sizes[TAKEN]:sizes[TAKEN] + k] = beyond
    sizes[TAKEN] += k
    corners = mesh_faces[beyond]
    vertices, vertex_points, point_vertices = new_rows_and_points(corners, welded, row_of, point_of, n_rows,
                                                                   n_points)
    p, r = point_vertices.shape[0], vertices.shape[0]
    faces, points, made = _with_room(faces, n + k, points, n_points + p, made, n_rows + r)
    for i in range(p):
        points[0][n_points + i] = positions[point_vertices[i]]
        points[1][n_points + i] = welded[point_vertices[i]]
    points[2][n_points:n_points + p] = _signed_distances(points[0][:n_points + p], n_points, start, end, radius)
    for i in range(r):
        j = n_rows + i
        made[0][j], made[1][j], made[3][j] = vertex_points[i], vertices[i], 0.0
        made[2][j, 0] = made[2][j, 1] = j          # (an input row is itself)
    for i in range(k):
        for c in range(3):
            faces[0][n + i, c] = row_of[corners[i, c]]
        faces[1][n + i], faces[4][n + i] = beyond[i], YES
    sizes[FACES], sizes[POINTS], sizes[ROWS] = n + k, n_points + p, n_rows + r
    _describe(faces, np.arange(n, n + k), points, made[0], start, end, radius, step)
    emap = with_room(emap, n + k, 3 * k)
    marks = _room_to_mark(marks, emap)
    for g in range(n, n + k):
        add_face_edges(emap, faces[2], g)
    return faces, points, made, taken, emap, marks


@helper
def _split(followed, faces, points, made, sizes, emap, marks, start, end, radius, step):
    """Split the faces on the marked edges ``followed`` (k,) where they are (``bisection.halves``: the
    first part takes the face's place, the others come last): one new point per marked edge (its
    welded points' midpoint), one new row per marked vertex edge; the marks cleared. Returns the grown
    records."""
    marked = marks[0]
    n, n_points, n_rows, k = sizes[FACES], sizes[POINTS], sizes[ROWS], followed.shape[0]
    split_faces, n_split, listed = np.empty(2 * k, np.int64), 0, np.zeros(n, np.bool_)
    for i in range(k):
        incidence = emap[3][followed[i]]
        while incidence >= 0:
            g = incidence // 3
            if not listed[g]:
                listed[g] = True
                split_faces = grown(split_faces, n_split + 1)
                split_faces[n_split] = g
                n_split += 1
            incidence = emap[4][incidence]
    room = 3 * n_split             # (at most: a face with j marked edges becomes j + 1 faces)
    faces, points, made = _with_room(faces, n + room, points, n_points + k, made, n_rows + room)
    point_of_edge = np.full(emap[6][0], -1, np.int64)
    for i in range(k):
        code = emap[2][followed[i]]
        a, b = code >> 32, code & LOW_BITS
        for c in range(3):
            points[0][n_points + i, c] = 0.5 * (points[0][a, c] + points[0][b, c])
        points[1][n_points + i] = NEW_POINT
        point_of_edge[followed[i]] = n_points + i
    points[2][n_points:n_points + k] = _signed_distances(points[0][:n_points + k], n_points, start, end, radius)
    sizes[POINTS] += k
    rows, sources, wanted = faces[0], faces[1], faces[4]
    row_table = code_table(3 * n_split)
    row_ids = np.empty(row_table.shape[0], np.int64)
    parts, made_from = np.empty((4, 3), np.int64), np.empty(4, np.int64)
    corners, mids = np.empty(3, np.int64), np.empty(3, np.int64)
    emap = with_room(emap, n + room, 3 * (n_split + room))
    for i in range(n_split):
        f = split_faces[i]
        for c in range(3):
            corners[c], mids[c] = rows[f, c], -1
            if marked[emap[5][f, c]]:
                a, b = rows[f, c], rows[f, (c + 1) % 3]
                at = slot(row_table, pair(a, b))
                if row_table[at] == EMPTY:
                    row_table[at], row_ids[at] = pair(a, b), n_rows
                    made[0][n_rows], made[1][n_rows], made[3][n_rows] = point_of_edge[emap[5][f, c]], -1, 0.5
                    made[2][n_rows, 0], made[2][n_rows, 1] = min(a, b), max(a, b)
                    n_rows += 1
                mids[c] = row_ids[at]
        count = halves(parts, made_from, 0, f, corners, mids, made[0], points[0])
        remove_face_edges(emap, f)
        rows[f] = parts[0]
        for j in range(1, count):
            rows[n], sources[n], wanted[n] = parts[j], sources[f], wanted[f]
            n += 1
    changed = np.concatenate((split_faces[:n_split], np.arange(sizes[FACES], n)))
    sizes[FACES], sizes[ROWS] = n, n_rows
    _describe(faces, changed, points, made[0], start, end, radius, step)
    for f in changed:
        add_face_edges(emap, faces[2], f)
    marked[followed] = False
    return faces, points, made, emap, _room_to_mark(marks, emap)


@helper
def _with_room(faces, n_faces, points, n_points, made, n_rows):
    """The records with room for ``n_faces`` faces, ``n_points`` points and ``n_rows`` rows."""
    faces = (grown(faces[0], n_faces), grown(faces[1], n_faces), grown(faces[2], n_faces), grown(faces[3], n_faces),
             grown(faces[4], n_faces))
    points = (grown(points[0], n_points), grown(points[1], n_points), grown(points[2], n_points))
    made = (grown(made[0], n_rows), grown(made[1], n_rows), grown(made[2], n_rows), grown(made[3], n_rows))
    return faces, points, made


@helper
def _room_to_mark(marks, emap):
    """``marks`` with a row for every edge an ``edge_map`` has room for (unmarked where grown)."""
    marked, stack = marks
    before = marked.shape[0]
    marked, stack = grown(marked, emap[2].shape[0]), grown(stack, emap[2].shape[0])
    marked[before:] = False
    return marked, stack


@inlined
def _mark(marked, stack, depth, e):
    """Mark edge e (once: pushed on ``stack`` to be followed); the stack's new depth."""
    if not marked[e]:
        marked[e] = True
        stack[depth] = e
        depth += 1
    return depth


@helper
def _describe(faces, changed, points, row_point, start, end, radius, step):
    """For the faces ``changed`` (k,) of the ``faces`` record, in place: their edges' codes, the corner
    whose edge is longest, and whether each is to be split: longer than ``step`` and crossed by the
    bit's surface (``bit.surface_crosses``). Asked only where ``wanted`` is ``YES`` (a new face, or a
    part of one that was): a part of a face that was not is not either (it is shorter, and inside or
    outside the bit where the face was)."""
    rows, codes, longest, wanted = faces[0], faces[2], faces[3], faces[4]
    positions, signed, x = points[0], points[2], np.empty(3)
    for f in changed:
        p, q, r = row_point[rows[f, 0]], row_point[rows[f, 1]], row_point[rows[f, 2]]
        codes[f, 0], codes[f, 1], codes[f, 2] = pair(p, q), pair(q, r), pair(r, p)
        longest[f], squared = longest_edge(positions, p, q, r)
        if wanted[f] == YES:
            wanted[f] = YES if squared > step * step and surface_crosses(
                positions, p, q, r, signed, math.sqrt(squared), start, end, radius, x) else NO


@helper
def _open_input_edge(emap, e, sources, point_welded, mesh, is_taken):
    """The input edge (its id in ``mesh``) that edge e of an ``edge_map`` of the patch's faces (from input
    faces ``sources``) is, if input faces not ``taken`` have it too; else -1. (An edge between two
    input points is an edge of the input face it lies in: bisection joins a new point to a corner.)"""
    code = emap[2][e]
    wa, wb = point_welded[code >> 32], point_welded[code & LOW_BITS]
    welded_faces, face_edges, offsets, edge_faces = mesh[3], mesh[4], mesh[5], mesh[6]
    incidence = emap[3][e]
    while wa != NEW_POINT and wb != NEW_POINT and incidence >= 0:
        s = sources[incidence // 3]
        incidence = emap[4][incidence]
        if s < 0:
            continue
        for j in range(3):
            u, v = welded_faces[s, j], welded_faces[s, (j + 1) % 3]
            if (u == wa and v == wb) or (u == wb and v == wa):
                edge = face_edges[s, j]
                for i in range(offsets[edge], offsets[edge + 1]):
                    if not is_taken[edge_faces[i]]:
                        return edge
                return -1
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
