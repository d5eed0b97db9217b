"""The rim placed and the inside taken away: the refined patch's faces classified against the bit.

Every point of the patch is outside the bit (f > tolerance), inside (f < -tolerance) or on its surface.
A face with no corner inside stays (one with every corner on the surface stays when its centre is
outside); a face with no corner outside goes; a face with corners on both sides keeps its outside part,
a triangle or a convex quad (two triangles over the shorter diagonal), whose new corners lie where its
edges cross the bit's surface (``bit.crossings``: one point per welded edge, so a seam's copies meet).
"""
from __future__ import annotations

import numpy as np

from .bit import crossings, signed_distances
from .patch import Patch

OUTSIDE, ON, INSIDE = 1, 0, -1


def open_hole(patch: Patch, bit, tolerance: float) -> tuple:
    """Replace the patch's faces by their parts outside the bit.

    returns (rim rows (list of row ids on the bit's surface that a kept face uses), the number of
    faces taken away or cut)
    """
    start, end, radius = bit
    points = patch.point_array()
    f = signed_distances(points, start, end, radius)
    side = np.where(f > tolerance, OUTSIDE, np.where(f < -tolerance, INSIDE, ON))
    rows = np.asarray(patch.faces, np.int64).reshape(-1, 3)
    sides = side[np.asarray(patch.row_point, np.int64)[rows]]
    has_inside, has_outside = (sides == INSIDE).any(axis=1), (sides == OUTSIDE).any(axis=1)
    kept = ~has_inside & has_outside
    on_surface = np.flatnonzero(~has_inside & ~has_outside)     # every corner on the surface: kept if outside
    kept[on_surface] = _centres_outside(points, patch, rows[on_surface], bit)
    crossing = has_inside & has_outside
    faces = rows[kept].tolist()
    sources = np.asarray(patch.face_source)[kept].tolist()
    opened = len(rows) - int(kept.sum())
    crossed = {}                            # (point, point), lower id first -> crossing point id
    pending = []                            # faces to finish once the crossings are placed
    for corners, source, s in zip(rows[crossing].tolist(), np.asarray(patch.face_source)[crossing].tolist(),
                                  sides[crossing].tolist()):
        for k in range(3):
            if s[k] * s[(k + 1) % 3] == -1:
                crossed.setdefault(patch.point_edge(corners[k], corners[(k + 1) % 3]), None)
        pending.append((corners, source, s))
    _place(patch, points, crossed, bit)
    kept_rows = rows[kept].ravel()
    rim = set(kept_rows[side[np.asarray(patch.row_point, np.int64)[kept_rows]] == ON].tolist())
    for corners, source, s in pending:
        polygon = []
        for k in range(3):
            a, b = corners[k], corners[(k + 1) % 3]
            if s[k] != INSIDE:
                polygon.append(a)
            if s[k] * s[(k + 1) % 3] == -1:
                polygon.append(_crossing_row(patch, a, b, crossed))
                rim.add(polygon[-1])
        for tri in _triangles(patch, polygon):
            faces.append(tri)
            sources.append(source)
    patch.faces, patch.face_source = faces, sources
    return sorted(rim), opened


def _centres_outside(points, patch: Patch, rows, bit) -> np.ndarray:
    """(F,) whether each face's centre is outside the bit."""
    centres = points[np.asarray(patch.row_point, np.int64)[rows]].mean(axis=1)
    return signed_distances(np.ascontiguousarray(centres), bit.start, bit.end, bit.radius) > 0.0


def _place(patch: Patch, points, crossed: dict, bit) -> None:
    """Each crossed edge's point on the bit's surface, from its lower point id (one per welded edge)."""
    if not crossed:
        return
    edges = np.array(list(crossed), np.int64).reshape(-1, 2)
    ts, xs = crossings(points, edges, bit.start, bit.end, bit.radius)
    for (key, t, x) in zip(list(crossed), ts, xs):
        crossed[key] = (patch.add_point(x), float(t))


def _crossing_row(patch: Patch, a: int, b: int, crossed: dict) -> int:
    """The row on vertex edge a-b where it crosses the bit (one per vertex edge: a seam's copies each get
    theirs, at the edge's one point)."""
    key = (a, b) if a < b else (b, a)
    r = patch.edge_rows.get(("rim",) + key)
    if r is not None:
        return r
    point, t = crossed[patch.point_edge(a, b)]
    if patch.row_point[key[0]] != min(patch.row_point[a], patch.row_point[b]):
        t = 1.0 - t                         # t runs from the lower point id
    return patch.new_row(point, key[0], key[1], t, ("rim",) + key)


def _triangles(patch: Patch, polygon: list) -> list:
    """A triangle, or a convex quad split on its shorter diagonal (both wound as the polygon)."""
    if len(polygon) == 3:
        return [polygon]
    p = patch.point_array()[[patch.row_point[r] for r in polygon]]
    if np.sum((p[0] - p[2]) ** 2) <= np.sum((p[1] - p[3]) ** 2):
        return [[polygon[0], polygon[1], polygon[2]], [polygon[0], polygon[2], polygon[3]]]
    return [[polygon[0], polygon[1], polygon[3]], [polygon[1], polygon[2], polygon[3]]]
