"""The rim placed and the inside taken away: the refined patch's faces classified against the bit.

Every point of the patch is outside the bit (f > tolerance), inside (f < -tolerance) or on its surface.
A face with no corner inside stays (one with every corner on the surface stays when its centre is
outside); a face with no corner outside goes; a face with corners on both sides keeps its outside part,
a triangle or a convex quad (two triangles over the shorter diagonal), whose new corners lie where its
edges cross the bit's surface (``bit.crossing``: one point per welded edge, so a seam's copies meet;
one row per vertex edge, so that each copy keeps its attributes). All of it is one compiled pass
(``_open``). Then ``rim_loop_edges`` finds the rims' edges, the new boundary on the surface, and chains
them into loops.
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F1, F2, I1, I2, f8, helper, i8, kernel
from .bisection import EMPTY, code_table, pair, slot
from .bit import crossing, put_on_edge, segment_distance, signed_distances
from ..loops import chained_edges
from .patch import Patch, put_face, squared_distance

OUTSIDE, ON, INSIDE = 1, 0, -1


def open_hole(patch: Patch, bit, tolerance: float) -> tuple:
    """Replace the patch's faces by their parts outside the bit (``_open``).

    returns (rim rows (sorted (r,) row ids on the bit's surface that a face uses), the number of faces
    taken away or cut)
    """
    faces, sources, points, row_points, row_parents, row_t, rim, opened = _open(
        patch.point_array(), patch.faces, patch.face_source, patch.row_point, bit.start, bit.end, bit.radius,
        tolerance)
    patch.add_points(points)
    patch.new_rows(row_points, row_parents[:, 0], row_parents[:, 1], row_t)
    patch.replace_faces(faces, sources)
    return rim, opened


@kernel((F2, I2, I1, I1, F1, F1, f8, f8), cost=3.0)
def _open(points, rows, sources, row_point, start, end, radius, tolerance):
    """The patch's faces ``rows`` (F, 3) (from input faces ``sources`` (F,); ``row_point`` (R,) the point
    of each row, ``points`` (P, 3)) replaced by their parts outside the bit: each point is outside (f >
    ``tolerance``), inside (f < -``tolerance``) or on the surface; the faces kept, in order, then the
    parts (``_outside_parts``).

    Returns (faces (G, 3), their sources (G,), the new points (p, 3), the new rows' points (r,), parents
    (r, 2) and t (r,) (``Patch.new_rows``; ids after the patch's), the rim rows (ascending: rows on the
    surface that a face uses), the number of faces taken away or cut)."""
    n, n_points = rows.shape[0], points.shape[0]
    signed = signed_distances(points, 0, start, end, radius)
    side = np.empty(n_points, np.int64)
    for p in range(n_points):
        side[p] = OUTSIDE if signed[p] > tolerance else (INSIDE if signed[p] < -tolerance else ON)
    kept, crossed = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    for f in range(n):
        inside = outside = False
        for k in range(3):
            inside |= side[row_point[rows[f, k]]] == INSIDE
            outside |= side[row_point[rows[f, k]]] == OUTSIDE
        kept[f], crossed[f] = outside and not inside, outside and inside
        if not (inside or outside):                 # every corner on the surface: kept if its centre is outside
            kept[f] = _centre_outside(points, row_point, rows, f, start, end, radius)
    crossing_rows, new_points, row_points, row_parents, row_t = _crossing_rows(
        points, rows, crossed, row_point, side, signed, start, end, radius)
    all_points = np.concatenate((points, new_points))
    all_row_point = np.concatenate((row_point, row_points))
    parts, part_of = _outside_parts(rows, crossed, side, crossing_rows, all_points, all_row_point)
    n_kept = 0
    for f in range(n):
        n_kept += kept[f]
    out, out_sources = np.empty((n_kept + parts.shape[0], 3), np.int64), np.empty(n_kept + parts.shape[0], np.int64)
    at = 0
    for f in range(n):
        if kept[f]:
            out[at, 0], out[at, 1], out[at, 2], out_sources[at] = rows[f, 0], rows[f, 1], rows[f, 2], sources[f]
            at += 1
    for i in range(parts.shape[0]):
        out[at, 0], out[at, 1], out[at, 2], out_sources[at] = parts[i, 0], parts[i, 1], parts[i, 2], \
            sources[part_of[i]]
        at += 1
    on_rim = np.zeros(all_row_point.shape[0], np.bool_)     # (the new points are on the surface)
    for r in out.ravel():
        p = all_row_point[r]
        on_rim[r] = p >= n_points or side[p] == ON
    return out, out_sources, new_points, row_points, row_parents, row_t, np.flatnonzero(on_rim), n - n_kept


@helper
def _centre_outside(points, row_point, rows, f, start, end, radius):
    """Whether the centre of face f of ``rows`` is outside the bit."""
    centre = np.zeros(3)
    for k in range(3):
        for c in range(3):
            centre[c] += points[row_point[rows[f, k]], c] / 3.0
    return segment_distance(start, end, end - start, centre) - radius > 0.0


@helper
def _crossing_rows(points, rows, crossed, row_point, side, signed, start, end, radius):
    """Where the corner edges of the ``crossed`` (F,) faces of ``rows`` that join a point inside the bit to
    one outside cross its surface: one new point per welded edge, placed from its lower point id
    (``bit.crossing``), and one new row per vertex edge (ids after ``points`` (P, 3) and ``row_point``
    (R,)). Returns (the row (F, 3) on each corner edge k -> k+1, -1 where none; the new points (p, 3);
    the new rows' points (r,), parents (r, 2) (lower row first) and t (r,) from the first parent)."""
    n, n_points, n_rows = rows.shape[0], points.shape[0], row_point.shape[0]
    out = np.full((n, 3), -1, np.int64)
    row_table, point_table = code_table(3 * n), code_table(3 * n)
    row_id, point_id = np.empty(row_table.shape[0], np.int64), np.empty(point_table.shape[0], np.int64)
    new_points, point_t = np.empty((3 * n, 3)), np.empty(3 * n)
    row_points, row_parents, row_t = np.empty(3 * n, np.int64), np.empty((3 * n, 2), np.int64), np.empty(3 * n)
    axis, x = end - start, np.empty(3)
    made_points = made_rows = 0
    for f in range(n):
        if not crossed[f]:
            continue
        for k in range(3):
            a, b = rows[f, k], rows[f, (k + 1) % 3]
            pa, pb = row_point[a], row_point[b]
            if side[pa] * side[pb] != -1:
                continue
            at = slot(row_table, pair(a, b))
            if row_table[at] == EMPTY:
                point_at = slot(point_table, pair(pa, pb))
                if point_table[point_at] == EMPTY:
                    lo, hi = min(pa, pb), max(pa, pb)
                    point_t[made_points] = crossing(points[lo], points[hi], signed[lo], signed[hi], start, end, axis,
                                                    radius, x)
                    put_on_edge(points[lo], points[hi], point_t[made_points], new_points[made_points])
                    point_table[point_at], point_id[point_at] = pair(pa, pb), made_points
                    made_points += 1
                lower, upper = min(a, b), max(a, b)
                t = point_t[point_id[point_at]]
                row_table[at], row_id[at] = pair(a, b), n_rows + made_rows
                row_points[made_rows] = n_points + point_id[point_at]
                row_parents[made_rows, 0], row_parents[made_rows, 1] = lower, upper
                row_t[made_rows] = t if row_point[lower] < row_point[upper] else 1.0 - t   # (t from the lower point)
                made_rows += 1
            out[f, k] = row_id[at]
    return (out, new_points[:made_points].copy(), row_points[:made_rows].copy(), row_parents[:made_rows].copy(),
            row_t[:made_rows].copy())


@helper
def _outside_parts(rows, crossed, side, crossing_rows, points, row_point):
    """The part outside the bit of each ``crossed`` (F,) face of ``rows`` (F, 3) (corners on both sides of
    its surface: ``side`` per point), its corner edges crossing the surface at ``crossing_rows`` (F, 3)
    (-1: no crossing): a triangle, or a convex quad split on its shorter diagonal (both wound as the
    face). Returns faces (T, 3) and the face (T,) each is part of."""
    n = rows.shape[0]
    out, part_of = np.empty((2 * n, 3), np.int64), np.empty(2 * n, np.int64)
    polygon = np.empty(4, np.int64)
    count = 0
    for f in range(n):
        if not crossed[f]:
            continue
        corners = 0
        for k in range(3):
            if side[row_point[rows[f, k]]] != INSIDE:
                polygon[corners] = rows[f, k]
                corners += 1
            if crossing_rows[f, k] >= 0:
                polygon[corners] = crossing_rows[f, k]
                corners += 1
        if corners == 3:
            count = put_face(out, part_of, count, f, polygon[0], polygon[1], polygon[2])
            continue
        if squared_distance(points, row_point[polygon[0]], row_point[polygon[2]]) <= \
                squared_distance(points, row_point[polygon[1]], row_point[polygon[3]]):
            count = put_face(out, part_of, count, f, polygon[0], polygon[1], polygon[2])
            count = put_face(out, part_of, count, f, polygon[0], polygon[2], polygon[3])
        else:
            count = put_face(out, part_of, count, f, polygon[0], polygon[1], polygon[3])
            count = put_face(out, part_of, count, f, polygon[1], polygon[2], polygon[3])
    return out[:count].copy(), part_of[:count].copy()


@kernel((I2, I1, I1, i8), cost=0.6, fused=True)
def rim_loop_edges(rows, row_point, rim, n_points):
    """The rims' boundary edges (``_rim_edges``: the rows of their tails (e,) and heads (e,), their
    points (e,), (e,)) and their loops over the points as ``loops.directed_loops`` chains them
    (``loops.chained_edges``: the loops' edges (k,) and offsets (l + 1,)), in one compiled call."""
    tails, heads, a, b = _rim_edges(rows, row_point, rim, n_points)
    edges, offsets = chained_edges(a, b)
    return tails, heads, a, b, edges, offsets


@helper
def _rim_edges(rows, row_point, rim, n_points):
    """The boundary edges between rim points (the points of the rows ``rim`` (r,), of ``n_points``) of
    the faces ``rows`` (F, 3) (``row_point`` (R,) the point of each row; an edge is a boundary if one
    corner edge of one face has its two points), in the faces' order, each in its face's direction: the
    rows of their tails (e,) and heads (e,), and their points (e,), (e,)."""
    on_rim = np.zeros(n_points, np.bool_)
    for r in rim:
        on_rim[row_point[r]] = True
    n = rows.shape[0]
    tails, heads, codes = np.empty(3 * n, np.int64), np.empty(3 * n, np.int64), np.empty(3 * n, np.int64)
    count = 0
    for f in range(n):
        for k in range(3):
            a, b = row_point[rows[f, k]], row_point[rows[f, (k + 1) % 3]]
            if on_rim[a] and on_rim[b]:
                tails[count], heads[count], codes[count] = rows[f, k], rows[f, (k + 1) % 3], pair(a, b)
                count += 1
    table = code_table(count)
    sides = np.zeros(table.shape[0], np.int64)          # (how many corner edges each code has)
    for i in range(count):
        at = slot(table, codes[i])
        table[at] = codes[i]
        sides[at] += 1
    n_edges = 0
    for i in range(count):
        if sides[slot(table, codes[i])] == 1:
            tails[n_edges], heads[n_edges] = tails[i], heads[i]
            n_edges += 1
    tail_points, head_points = np.empty(n_edges, np.int64), np.empty(n_edges, np.int64)
    for e in range(n_edges):
        tail_points[e], head_points[e] = row_point[tails[e]], row_point[heads[e]]
    return tails[:n_edges].copy(), heads[:n_edges].copy(), tail_points, head_points
