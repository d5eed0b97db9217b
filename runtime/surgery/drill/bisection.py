"""One round of longest-edge bisection in compiled code (``refine.py`` runs the rounds): each face's
longest edge, the closure of the marked edges (a face with a marked edge marks its longest), and the
faces split on their marked edges, with one new row per vertex edge and one new point per welded edge.

Edges are ``patch.pair_codes`` of their two point ids (welded: a seam's copies are one edge) or row ids;
the sets and maps of codes are open-addressing hash tables (``_table``, ``_slot``): no sort.
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F2, I1, I2, helper, i8, kernel
from .patch import put_face, squared_distance

#: an empty slot of a ``_table``
EMPTY = -1


@helper
def _table(count):
    """An empty table (a power of two >= 2 count + 2 slots of ``EMPTY``) for up to ``count`` codes."""
    size = 4
    while size < 2 * count + 2:
        size *= 2
    return np.full(size, EMPTY, np.int64)


@helper
def _slot(table, code):
    """The slot of ``code`` (>= 0) in ``table``: where it is, or the empty slot where it goes (linear
    probing from a multiplicative hash; the table is never full)."""
    mask = table.shape[0] - 1
    at = ((code ^ (code >> 29)) * 0x9E3779B1) & mask
    while table[at] != EMPTY and table[at] != code:
        at = (at + 1) & mask
    return at


@helper
def _pair(a, b):
    """``patch.pair_codes`` of one pair of ids."""
    return (min(a, b) << 32) | max(a, b)


@kernel((F2, I2), cost=0.2)
def longest_edges(points, face_points):
    """(F,) the corner k whose edge k -> k+1 is longest in each face (F, 3) of ``points`` (P, 3) (the
    first on a tie), (F,) its squared length."""
    n = face_points.shape[0]
    longest, squared = np.zeros(n, np.int64), np.full(n, -1.0)
    for f in range(n):
        for k in range(3):
            d = squared_distance(points, face_points[f, k], face_points[f, (k + 1) % 3])
            if d > squared[f]:
                longest[f], squared[f] = k, d
    return longest, squared


@kernel((I2, I1, I1), cost=0.3)
def closure(codes, longest, chosen):
    """The edge codes ``chosen`` (k,) and the longest edge ``longest[f]`` (F,) of every face f with a
    marked edge among ``codes[f]`` (F, 3), until none is added: the marked codes (m,), in no order."""
    table = _table(codes.shape[0] + chosen.shape[0])
    marked = np.empty(codes.shape[0] + chosen.shape[0], np.int64)
    count = 0
    for code in chosen:
        at = _slot(table, code)
        if table[at] == EMPTY:
            table[at] = marked[count] = code
            count += 1
    added = True
    while added:
        added = False
        for f in range(codes.shape[0]):
            at = _slot(table, longest[f])
            if table[at] != EMPTY:
                continue
            for k in range(3):
                if table[_slot(table, codes[f, k])] == codes[f, k]:
                    table[at] = marked[count] = longest[f]
                    count += 1
                    added = True
                    break
    return marked[:count].copy()


@kernel((I2, I1, F2, I1, i8, i8), cost=0.5)
def split_marked(rows, row_point, points, marked, first_row, first_point):
    """Split every face of ``rows`` (F, 3) with a marked edge (its points' code among ``marked`` (k,)):
    on its longest edge if that is marked (else the first marked), then each half on the other edge it
    keeps, if that is marked: 2 to 4 faces, wound as the face. Each marked vertex edge gets one new row
    (ids from ``first_row``) at its welded edge's one new point (ids from ``first_point``).

    Returns faces (G, 3): the faces not split, in order, then the halves; the face (G,) each is or
    comes from; the new rows' parents (r, 2) (lower row first) and points (r,); the new points'
    parents (p, 2) (the welded edge's points, lower first)."""
    n = rows.shape[0]
    marks = _table(marked.shape[0])
    for code in marked:
        marks[_slot(marks, code)] = code
    split = np.zeros((n, 3), np.bool_)
    count = 0
    for f in range(n):
        for k in range(3):
            code = _pair(row_point[rows[f, k]], row_point[rows[f, (k + 1) % 3]])
            if marks[_slot(marks, code)] == code:
                split[f, k] = True
                count += 1
    row_table, point_table = _table(count), _table(count)
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
            at = _slot(row_table, _pair(a, b))
            if row_table[at] == EMPTY:
                pa, pb = row_point[a], row_point[b]
                point_at = _slot(point_table, _pair(pa, pb))
                if point_table[point_at] == EMPTY:
                    point_table[point_at], point_id[point_at] = _pair(pa, pb), first_point + points_made
                    point_parents[points_made, 0], point_parents[points_made, 1] = min(pa, pb), max(pa, pb)
                    points_made += 1
                row_table[at], row_id[at] = _pair(a, b), first_row + rows_made
                row_parents[rows_made, 0], row_parents[rows_made, 1] = min(a, b), max(a, b)
                row_points[rows_made] = point_id[point_at]
                rows_made += 1
            midpoint[f, k] = row_id[at]
    out, made_from = np.empty((n + 3 * n, 3), np.int64), np.empty(n + 3 * n, np.int64)
    made = 0
    for f in range(n):
        if not (split[f, 0] or split[f, 1] or split[f, 2]):
            made = put_face(out, made_from, made, f, rows[f, 0], rows[f, 1], rows[f, 2])
    for f in range(n):
        if split[f, 0] or split[f, 1] or split[f, 2]:
            made = _halves(out, made_from, made, f, rows, row_point, points, midpoint)
    return (out[:made].copy(), made_from[:made].copy(), row_parents[:rows_made].copy(), row_points[:rows_made].copy(),
            point_parents[:points_made].copy())


@helper
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
