"""The part of a mesh that a drill works on: its faces as rows of the vertex table, its points, and how
each new row is made.

Faces are rows of the vertex table (attribute-split copies kept apart: a seam edge bisected gets one new
row per copy, all at one position); points are the welded vertices (one position per place). A new row
blends two earlier rows, (1 - t) a + t b (a midpoint, a rim's crossing, a wall's row between two rims);
``descriptions`` resolves every row into input vertices and coefficients, from which its weights and
attributes are made (``new_vertices.py``).
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F1, I1, I2, kernel
from ..new_vertices import accumulate, largest_first

#: input vertices a new vertex is described by at most: 3 in a face, 6 on a wall (between two rims)
SOURCES = 6


class Patch:
    """The refined part of a mesh around a bit.

    point_array() : (P, 3) float64, one position per welded vertex of the patch and per new point
    point_of : dict welded id of the input -> point id (input vertices); point_welded : its inverse (new
        points have no welded id)
    row_point : list of point ids, the point of each row (rows: input vertex ids first as met, then new)
    row_vertex : list, the input vertex of each row (-1 for a new one) ; row_parents : list of (a, b, t):
        a new row blends earlier rows a and b as (1 - t) a + t b (``descriptions`` resolves them)
    row_of : dict input vertex id -> row id ; input_rows : the input vertices' rows
    faces : list of [row, row, row] ; face_source : list of the input face each descends from
    edge_rows : dict (row, row) -> the row at the midpoint of that vertex edge (lower row first), and
        ("rim", row, row) -> the row where that vertex edge crosses the bit's surface
    midpoints : dict (point, point) -> the point at their midpoint ; taken : set of the input faces taken
    fill_params : dict point id -> (θ, σ) on the bit's surface, for the points of a wall's fill
    """

    def __init__(self, positions, faces, topology):
        self.positions, self.mesh_faces, self.topology = positions, faces, topology
        self._points, self.n_points, self.point_of, self.point_welded = np.empty((64, 3)), 0, {}, {}
        self.row_point, self.row_vertex, self.row_parents, self.row_of, self.input_rows = [], [], [], {}, []
        self.faces, self.face_source, self.edge_rows, self.midpoints = [], [], {}, {}
        self.taken = set()
        self.fill_params = {}

    # -- building ------------------------------------------------------------------------------------
    def row(self, v: int) -> int:
        """The row of input vertex v (added on first use)."""
        r = self.row_of.get(v)
        if r is None:
            w = int(self.topology.welded[v])
            p = self.point_of.get(w)
            if p is None:
                p = self.point_of[w] = self.add_point(self.positions[v])
                self.point_welded[p] = w
            r = self.row_of[v] = len(self.row_point)
            self.row_point.append(p)
            self.row_vertex.append(v)
            self.row_parents.append((r, r, 0.0))
            self.input_rows.append(r)
        return r

    def take_all(self, faces) -> None:
        """Add the input faces ``faces`` (k,) to the empty patch: what ``take`` of each would make (rows
        in ascending vertex order, points in the order their first vertex comes), in whole arrays."""
        assert not self.row_point, "take_all starts a patch"
        corners = self.mesh_faces[faces]
        vertices = np.unique(corners)
        welded, first, point = np.unique(self.topology.welded[vertices], return_index=True, return_inverse=True)
        order = np.argsort(first)                   # the points by their first vertex
        renumber = np.empty(len(order), np.int64)
        renumber[order] = np.arange(len(order))
        point = renumber[point.ravel()]
        self.add_points(self.positions[vertices[first[order]]])
        welded = welded[order].tolist()
        self.point_of, self.point_welded = dict(zip(welded, range(len(welded)))), dict(enumerate(welded))
        rows = list(range(len(vertices)))
        self.row_of = dict(zip(vertices.tolist(), rows))
        self.row_point, self.row_vertex, self.input_rows = point.tolist(), vertices.tolist(), rows[:]
        self.row_parents = [(r, r, 0.0) for r in rows]
        self.faces.extend(np.searchsorted(vertices, corners).tolist())
        self.face_source.extend(faces.tolist())
        self.taken.update(faces.tolist())

    def take(self, face: int) -> bool:
        """Add input face ``face`` to the patch (once); whether it was added."""
        if face in self.taken:
            return False
        self.taken.add(face)
        self.faces.append([self.row(int(v)) for v in self.mesh_faces[face]])
        self.face_source.append(face)
        return True

    def midpoint_row(self, a: int, b: int, place=None) -> int:
        """The row at the midpoint of vertex edge a-b (made once; a seam edge's copies share its point);
        ``place(point, point)``, when given, says where the midpoint of two points goes instead (a
        wall's, on the bit's surface) and is called just before the new point is added."""
        key = (a, b) if a < b else (b, a)
        r = self.edge_rows.get(key)
        if r is not None:
            return r
        pa, pb = self.row_point[a], self.row_point[b]
        point_key = (pa, pb) if pa < pb else (pb, pa)
        p = self.midpoints.get(point_key)
        if p is None:
            points = self._points
            p = self.midpoints[point_key] = self.add_point(
                0.5 * (points[point_key[0]] + points[point_key[1]]) if place is None else place(*point_key))
        return self.new_row(p, a, b, 0.5, key)

    def new_row(self, point: int, a: int, b: int, t: float, key: tuple | None = None) -> int:
        """A new row at ``point`` whose weights and attributes blend rows a and b as (1 - t) a + t b; kept
        under ``key`` in ``edge_rows`` if given."""
        r = len(self.row_point)
        if key is not None:
            self.edge_rows[key] = r
        self.row_point.append(point)
        self.row_vertex.append(-1)
        self.row_parents.append((a, b, t))
        return r

    def descriptions(self) -> tuple:
        """(src (R, SOURCES) int64, coef (R, SOURCES) float64): each row as input vertices and their
        coefficients (``_descriptions``)."""
        parents = np.array([(a, b) for a, b, _ in self.row_parents], np.int64).reshape(-1, 2)
        t = np.array([t for _, _, t in self.row_parents], np.float64)
        return _descriptions(np.array(self.row_vertex, np.int64), parents, t)

    def point_edge(self, a: int, b: int) -> tuple:
        pa, pb = self.row_point[a], self.row_point[b]
        return (pa, pb) if pa < pb else (pb, pa)

    # -- arrays --------------------------------------------------------------------------------------
    def point_array(self) -> np.ndarray:
        """(P, 3) the points so far (a view, valid until the next point is added)."""
        return self._points[:self.n_points]

    def add_point(self, position) -> int:
        """A new point at ``position`` (3,); its id."""
        if self.n_points == len(self._points):
            self._points = np.concatenate([self._points, np.empty_like(self._points)])
        self._points[self.n_points] = position
        self.n_points += 1
        return self.n_points - 1

    def add_points(self, positions) -> int:
        """New points at ``positions`` (k, 3); the id of the first (the others follow)."""
        k = len(positions)
        while self.n_points + k > len(self._points):
            self._points = np.concatenate([self._points, np.empty_like(self._points)])
        self._points[self.n_points:self.n_points + k] = positions
        self.n_points += k
        return self.n_points - k

    def face_points(self) -> np.ndarray:
        rp = np.asarray(self.row_point, np.int64)
        return rp[np.asarray(self.faces, np.int64).reshape(-1, 3)]


@kernel((I1, I2, F1), cost=0.4)
def _descriptions(vertex, parents, t):
    """Rows as input vertices and coefficients: row r is input vertex ``vertex[r]`` (>= 0), or the blend
    (1 - t[r]) of row parents[r, 0] and t[r] of row parents[r, 1] (earlier rows), of whose input
    vertices the SOURCES with the largest coefficients are kept and renormalised (in one face there are
    at most three; between two rims six). Returns src (R, SOURCES) int64, coef (R, SOURCES) float64,
    largest first, unused slots the first vertex with 0."""
    rows = vertex.shape[0]
    src, coef = np.zeros((rows, SOURCES), np.int64), np.zeros((rows, SOURCES))
    keys, values = np.empty(2 * SOURCES, np.int64), np.empty(2 * SOURCES)
    for r in range(rows):
        if vertex[r] >= 0:
            src[r, :] = vertex[r]
            coef[r, 0] = 1.0
            continue
        if t[r] == 0.0 or t[r] == 1.0:        # a copy (a wall's row at a rim's point): bit for bit, so that
            p = parents[r, 0] if t[r] == 0.0 else parents[r, 1]     # a posed drill places both alike
            src[r, :], coef[r, :] = src[p, :], coef[p, :]
            continue
        count = 0
        for side in range(2):
            p = parents[r, side]
            scale = t[r] if side == 1 else 1.0 - t[r]
            for s in range(SOURCES):
                if coef[p, s] != 0.0:
                    count = accumulate(keys, values, count, src[p, s], scale * coef[p, s])
        kept = min(count, SOURCES)
        total = largest_first(keys, values, count, kept)
        for slot in range(SOURCES):
            src[r, slot] = keys[slot] if slot < kept else keys[0]
            coef[r, slot] = values[slot] / total if slot < kept else 0.0
    return src, coef
