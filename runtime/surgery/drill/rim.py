"""The rim placed and the inside taken away: the refined patch's faces classified against the bit.

Every point of the patch is outside the bit (f > tolerance), inside (f < -tolerance) or on its surface.
A face with no corner inside stays (one with every corner on the surface stays when its centre is
outside); a face with no corner outside goes; a face with corners on both sides keeps its outside part,
a triangle or a convex quad (two triangles over the shorter diagonal), whose new corners lie where its
edges cross the bit's surface (``bit.crossings``: one point per welded edge, so a seam's copies meet;
one row per vertex edge, so that each copy keeps its attributes).
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F2, I1, I2, kernel
from .bit import crossings, signed_distances
from .patch import LOW_BITS, Patch, edge_codes, pair_codes, put_face, squared_distance

OUTSIDE, ON, INSIDE = 1, 0, -1


def open_hole(patch: Patch, bit, tolerance: float) -> tuple:
    """Replace the patch's faces by their parts outside the bit.

    returns (rim rows (sorted (r,) row ids on the bit's surface that a face uses), the number of faces
    taken away or cut)
    """
    start, end, radius = bit
    points = patch.point_array()
    f = signed_distances(points, start, end, radius)
    side = np.where(f > tolerance, OUTSIDE, np.where(f < -tolerance, INSIDE, ON))
    rows, sources = patch.faces, patch.face_source
    sides = side[patch.row_point[rows]]
    has_inside, has_outside = (sides == INSIDE).any(axis=1), (sides == OUTSIDE).any(axis=1)
    kept = ~has_inside & has_outside
    on_surface = np.flatnonzero(~has_inside & ~has_outside)     # every corner on the surface: kept if outside
    kept[on_surface] = _centres_outside(points, patch, rows[on_surface], bit)
    crossing = has_inside & has_outside
    opened = len(rows) - int(kept.sum())
    crossing_rows = _crossing_rows(patch, rows[crossing], sides[crossing], bit)
    parts, part_of = _outside_parts(rows[crossing], sides[crossing], crossing_rows, patch.point_array(),
                                    patch.row_point)
    faces = np.concatenate([rows[kept], parts])
    patch.replace_faces(faces, np.concatenate([sources[kept], sources[crossing][part_of]]))
    on_bit = np.ones(patch.n_points, bool)         # (the points after the classified ones: crossings)
    on_bit[:len(side)] = side == ON
    used = np.zeros(patch.n_rows, bool)
    used[faces] = True
    return np.flatnonzero(used & on_bit[patch.row_point]), opened


def _centres_outside(points, patch: Patch, rows, bit) -> np.ndarray:
    """(F,) whether each face's centre is outside the bit."""
    centres = points[patch.row_point[rows]].mean(axis=1)
    return signed_distances(np.ascontiguousarray(centres), bit.start, bit.end, bit.radius) > 0.0


def _crossing_rows(patch: Patch, rows, sides, bit) -> np.ndarray:
    """(C, 3) the row where each corner edge k -> k+1 of faces ``rows`` (C, 3) crosses the bit's surface
    (``sides`` (C, 3) of its ends -1 and 1), -1 where it does not: one point per welded edge, placed from
    its lower point id (``bit.crossings``), and one row per vertex edge."""
    crossed = sides * np.roll(sides, -1, axis=1) == -1
    row_edges, row_edge_of = np.unique(edge_codes(rows)[crossed], return_inverse=True)
    row_a, row_b = row_edges >> 32, row_edges & LOW_BITS
    point_a, point_b = patch.row_point[row_a], patch.row_point[row_b]
    point_edges, point_edge_of = np.unique(pair_codes(point_a, point_b), return_inverse=True)
    edges = np.column_stack([point_edges >> 32, point_edges & LOW_BITS])
    ts, xs = crossings(patch.point_array(), edges, bit.start, bit.end, bit.radius)
    first_point = patch.add_points(xs)
    t = ts[point_edge_of]
    t = np.where(point_a < point_b, t, 1.0 - t)          # (t runs from the lower point id)
    first_row = patch.new_rows(first_point + point_edge_of, row_a, row_b, t)
    out = np.full(rows.shape, -1, np.int64)
    out[crossed] = first_row + row_edge_of
    return out


@kernel((I2, I2, I2, F2, I1), cost=0.3)
def _outside_parts(rows, sides, crossing_rows, points, row_point):
    """The part outside the bit of each face ``rows`` (C, 3) with corners on both sides (``sides`` (C, 3)),
    its corner edges crossing the surface at ``crossing_rows`` (C, 3) (-1: no crossing): a triangle, or
    a convex quad split on its shorter diagonal (both wound as the face). Returns faces (T, 3) and the
    face (T,) each is part of."""
    n = rows.shape[0]
    out, part_of = np.empty((2 * n, 3), np.int64), np.empty(2 * n, np.int64)
    polygon = np.empty(4, np.int64)
    count = 0
    for f in range(n):
        corners = 0
        for k in range(3):
            if sides[f, k] != INSIDE:
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
