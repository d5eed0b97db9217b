"""Longest-edge bisection in compiled code (``refine.py`` explains it; ``rounds.py`` closes the marks):
each face's longest edge, and the faces split on their marked edges, with one new row per vertex edge
and one new point per welded edge.

Edges are ``patch.pair_codes`` of their two point ids (welded: a seam's copies are one edge) or row ids;
the sets and maps of codes are open-addressing hash tables (``code_table``, ``slot``): no sort.
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F2, I1, I2, helper, i8, inlined, kernel
from .patch import put_face, squared_distance

#: an empty slot of a ``code_table``
EMPTY = -1


@helper
def code_table(count):
    """An empty table (a power of two >= 2 count + 2 slots of ``EMPTY``) for up to ``count`` codes."""
    size = 4
    while size < 2 * count + 2:
        size *= 2
    return np.full(size, EMPTY, np.int64)


@helper
def slot(table, code):
    """The slot of ``code`` (>= 0) in ``table`` (a ``code_table``): where it is, or the empty slot where it goes (linear
    probing from a multiplicative hash; the table is never full)."""
    mask = table.shape[0] - 1
    at = ((code ^ (code >> 29)) * 0x9E3779B1) & mask
    while table[at] != EMPTY and table[at] != code:
        at = (at + 1) & mask
    return at


@helper
def pair(a, b):
    """``patch.pair_codes`` of one pair of ids."""
    return (min(a, b) << 32) | max(a, b)


@helper
def has(table, code):
    """Whether ``code`` is in ``table`` (a ``code_table``)."""
    return table[slot(table, code)] == code


@inlined
def longest_edge(points, p, q, r):
    """(the corner k whose edge k -> k+1 of triangle p, q, r (rows of ``points``) is longest, the first on
    a tie; its squared length)."""
    k, longest = 0, squared_distance(points, p, q)
    d = squared_distance(points, q, r)
    if d > longest:
        k, longest = 1, d
    d = squared_distance(points, r, p)
    if d > longest:
        k, longest = 2, d
    return k, longest


@helper
def midpoints(points, pairs):
    """(k, 3) the midpoint of each pair (k, 2) of rows of ``points``."""
    out = np.empty((pairs.shape[0], 3))
    for i in range(pairs.shape[0]):
        for c in range(3):
            out[i, c] = 0.5 * (points[pairs[i, 0], c] + points[pairs[i, 1], c])
    return out


@kernel((I2, I1, F2, I1, i8, i8), cost=0.5)
def split_marked(rows, row_point, points, marked, first_row, first_point):
    """``split`` on the edges whose points' codes are among ``marked`` (k,)."""
    marks = code_table(marked.shape[0])
    for code in marked:
        marks[slot(marks, code)] = code
    on_marked = np.empty(rows.shape, np.bool_)
    for f in range(rows.shape[0]):
        for k in range(3):
            on_marked[f, k] = has(marks, pair(row_point[rows[f, k]], row_point[rows[f, (k + 1) % 3]]))
    faces, made_from, _, row_parents, row_points, point_parents = split(rows, row_point, points, on_marked,
                                                                          first_row, first_point)
    return faces, made_from, row_parents, row_points, point_parents


@helper
def split(rows, row_point, points, split, first_row, first_point):
    """Split every face of ``rows`` (F, 3) with a marked edge (``split`` (F, 3): whether each corner edge
    k -> k+1 is, alike on every face that has it): on its longest edge if that is marked (else the
    first marked), then each half on the other edge it keeps, if that is marked: 2 to 4 faces, wound as
    the face. Each marked vertex edge gets one new row (ids from ``first_row``) at its welded edge's one
    new point (ids from ``first_point``).

    Returns faces (G, 3): the faces not split, in order, then the halves; the face (G,) each is or
    comes from; how many are not split; the new rows' parents (r, 2) (lower row first) and points (r,);
    the new points' parents (p, 2) (the welded edge's points, lower first)."""
    n = rows.shape[0]
    count = 0
    for f in range(n):
        for k in range(3):
            count += split[f, k]
    row_table, point_table = code_table(count), code_table(count)
    row_id, point_id = np.empty(row_table.shape[0], np.int64), np.empty(point_table.shape[0], np.int64)
    row_parents, row_points, point_parents = np.empty((count, 2), np.int64), np.empty(count, np.int64), \
        np.empty((count, 2), np.int64)
    midpoint = np.full((n, 3), -1, np.int64)
    rows_made = points_made = 0
    for f in range(n):
        for k in range(3):
            if not split[f, k]:
                continue
            a, b = rows[f, k], rows[f, (k + 1) % 3]
            at = slot(row_table, pair(a, b))
            if row_table[at] == EMPTY:
                pa, pb = row_point[a], row_point[b]
                point_at = slot(point_table, pair(pa, pb))
                if point_table[point_at] == EMPTY:
                    point_table[point_at], point_id[point_at] = pair(pa, pb), first_point + points_made
                    point_parents[points_made, 0], point_parents[points_made, 1] = min(pa, pb), max(pa, pb)
                    points_made += 1
                row_table[at], row_id[at] = pair(a, b), first_row + rows_made
                row_parents[rows_made, 0], row_parents[rows_made, 1] = min(a, b), max(a, b)
                row_points[rows_made] = point_id[point_at]
                rows_made += 1
            midpoint[f, k] = row_id[at]
    # (a face with j marked edges becomes j + 1 faces)
    out, made_from = np.empty((n + count, 3), np.int64), np.empty(n + count, np.int64)
    made = 0
    for f in range(n):
        if not (split[f, 0] or split[f, 1] or split[f, 2]):
            made = put_face(out, made_from, made, f, rows[f, 0], rows[f, 1], rows[f, 2])
    kept = made
    for f in range(n):
        if split[f, 0] or split[f, 1] or split[f, 2]:
            made = _halves(out, made_from, made, f, rows, row_point, points, midpoint)
    return (out, made_from, kept, row_parents[:rows_made].copy(),
            row_points[:rows_made].copy(), point_parents[:points_made].copy())


@inlined
def _halves(out, made_from, made, f, rows, row_point, points, midpoint):
    """Write the faces that replace face f (``split_marked``) at row ``made`` of ``out``; the next row."""
    k, longest = -1, -1.0
    for j in range(3):
        d = squared_distance(points, row_point[rows[f, j]], row_point[rows[f, (j + 1) % 3]])
        if d > longest:
            k, longest = j, d
    if midpoint[f, k] < 0:
        k = 0
        while midpoint[f, k] < 0:
            k += 1
    a, b, c = rows[f, k], rows[f, (k + 1) % 3], rows[f, (k + 2) % 3]
    m, on_ca, on_bc = midpoint[f, k], midpoint[f, (k + 2) % 3], midpoint[f, (k + 1) % 3]
    # each half keeps one of the face's other two edges (c-a, b-c): bisected too where it is marked
    if on_ca >= 0:
        made = put_face(out, made_from, made, f, a, m, on_ca)
        made = put_face(out, made_from, made, f, m, c, on_ca)
    else:
        made = put_face(out, made_from, made, f, a, m, c)
    if on_bc >= 0:
        made = put_face(out, made_from, made, f, m, b, on_bc)
        made = put_face(out, made_from, made, f, m, on_bc, c)
    else:
        made = put_face(out, made_from, made, f, m, b, c)
    return made
