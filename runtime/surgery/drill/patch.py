"""The part of a mesh that a drill works on: its faces as rows of the vertex table, its points, and how
each new row is made.

Faces are rows of the vertex table (attribute-split copies kept apart: a seam edge bisected gets one new
row per copy, all at one position); points are the welded vertices (one position per place). A new row
blends two earlier rows, (1 - t) a + t b (a midpoint, a rim's crossing, a wall's row between two rims),
and so do its weights and attributes, row by row (``row_skins``, ``row_values``); ``descriptions``
resolves every row into input vertices and coefficients (``DrillResult.new``). Everything is kept in
arrays that grow (``_Growing``): the drill's steps read and make whole arrays of faces, rows and points
at a time.
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, F2, I1, I2, helper, i8, kernel
from ..gather import gather_rows
from ..new_vertices import DOMINANT, UNIT, accumulate, largest_first

#: input vertices a new vertex is described by at most: 3 in a face, 6 on a wall (between two rims)
SOURCES = 6
#: ``Patch.point_welded`` of a point the drill made
NEW_POINT = -1
#: the low 32 bits of a ``pair_codes`` code
LOW_BITS = 0xFFFFFFFF


def pair_codes(a, b) -> np.ndarray:
    """One int64 for each unordered pair of ids a, b (arrays of one shape, ids below 2^31): the lower id in
    the high 32 bits, the higher in the low (``LOW_BITS``); sorting the codes sorts the pairs."""
    return (np.minimum(a, b) << 32) | np.maximum(a, b)


def edge_codes(faces) -> np.ndarray:
    """(F, 3) ``pair_codes`` of each corner edge k -> k+1 of ``faces`` (F, 3) (of rows or of points)."""
    return pair_codes(faces, np.roll(faces, -1, axis=1))


class _Growing:
    """An array that rows are appended to, its capacity doubled when full; ``view()`` the rows so far."""

    def __init__(self, dtype, tail: tuple = ()):
        self._data, self.n = np.empty((4096,) + tail, dtype), 0      # (a hole makes a few thousand)

    def extend(self, rows) -> int:
        """Append ``rows`` (k, *tail); the index of the first."""
        self.add(len(rows))[:] = rows
        return self.n - len(rows)

    def add(self, k: int) -> np.ndarray:
        """Append k rows, unwritten; returns them (a view) for the caller to fill."""
        if self.n + k > len(self._data):
            grown = np.empty((max(2 * len(self._data), self.n + k),) + self._data.shape[1:], self._data.dtype)
            grown[:self.n] = self._data[:self.n]
            self._data = grown
        self.n += k
        return self._data[self.n - k:self.n]

    def replace(self, rows) -> None:
        self.n = 0
        self.extend(rows)

    def view(self) -> np.ndarray:
        """The rows so far (a view, valid until the next ``extend``)."""
        return self._data[:self.n]


class Patch:
    """The refined part of a mesh around a bit.

    point_array() : (P, 3) float64, the points: the welded vertices of the taken faces, then new ones
    point_welded : (P,) int64, the input's welded id of each point (``NEW_POINT`` for a new one)
    row_point : (R,) int64, the point of each row ; row_vertex : (R,) int64, the input vertex of each row
        (-1 for a new one) ; row_parents : (R, 2) int64 and row_t : (R,): a new row blends earlier rows
        as (1 - t) row_parents[:, 0] + t row_parents[:, 1]
    faces : (F, 3) int64 rows, wound as the input's ; face_source : (F,) int64, the input face each
        descends from (a wall's: negative, ``wall.WALL``)
    taken : (T,) int64, the input faces taken, in the order taken ; is_taken : (m,) bool, per input face
    row_of : (n,) int64, the row of each input vertex (-1: none) ; point_of : (w,) int64, the point of
        each of the input's welded vertices (-1: none)
    fill_params : dict point id -> (θ, σ) on the bit's surface, for the points of a wall's fill

    Input faces join it through ``rounds.refine_rounds`` (``grow``), new rows and faces through the
    other steps.
    """

    def __init__(self, positions, faces, topology):
        self.positions, self.mesh_faces, self.topology = positions, faces, topology
        self._points, self._point_welded = _Growing(np.float64, (3,)), _Growing(np.int64)
        self._row_point, self._row_vertex = _Growing(np.int64), _Growing(np.int64)
        self._row_parents, self._row_t = _Growing(np.int64, (2,)), _Growing(np.float64)
        self._faces, self._face_source, self._taken = _Growing(np.int64, (3,)), _Growing(np.int64), _Growing(np.int64)
        self.row_of, self.point_of = np.full(len(positions), -1, np.int64), np.full(topology.n_welded, -1, np.int64)
        self.is_taken = np.zeros(len(faces), bool)
        self.fill_params = {}

    point_welded = property(lambda self: self._point_welded.view())
    row_point = property(lambda self: self._row_point.view())
    row_vertex = property(lambda self: self._row_vertex.view())
    row_parents = property(lambda self: self._row_parents.view())
    row_t = property(lambda self: self._row_t.view())
    faces = property(lambda self: self._faces.view())
    face_source = property(lambda self: self._face_source.view())
    taken = property(lambda self: self._taken.view())
    n_points = property(lambda self: self._points.n)
    n_rows = property(lambda self: self._row_point.n)

    # -- building ------------------------------------------------------------------------------------
    def grow(self, made) -> None:
        """Take in what ``rounds.refine_rounds`` made (a ``Refined``; it updated the maps in place)."""
        self._add_points(made.points, made.point_welded)
        self.new_rows(made.row_points, made.row_parents[:, 0], made.row_parents[:, 1], made.row_t, made.row_vertex)
        self.replace_faces(made.rows, made.sources)
        self._taken.extend(made.taken)

    def new_rows(self, points, a, b, t, vertices=-1) -> int:
        """New rows at ``points`` (k,) whose weights and attributes blend rows a and b (k,) (or scalars)
        as (1 - t) a + t b; ``vertices`` (k,) the input vertex of each (-1: a new row). The first's id."""
        points = np.asarray(points, np.int64).reshape(-1)
        k = len(points)
        first = self._row_point.extend(points)
        self._row_vertex.add(k)[:] = vertices
        parents = self._row_parents.add(k)
        parents[:, 0], parents[:, 1] = a, b
        self._row_t.add(k)[:] = t
        return first

    def new_row(self, point: int, a: int, b: int, t: float) -> int:
        """One new row (``new_rows``); its id."""
        return self.new_rows([point], a, b, t)

    def add_faces(self, rows, sources) -> None:
        """Append faces ``rows`` (k, 3) descending from input faces ``sources`` (k,) (or one for all)."""
        rows = np.asarray(rows, np.int64).reshape(-1, 3)
        self._faces.extend(rows)
        self._face_source.add(len(rows))[:] = sources

    def replace_faces(self, rows, sources) -> None:
        """The patch's faces are now ``rows`` (k, 3) descending from ``sources`` (k,)."""
        self._faces.replace(np.asarray(rows, np.int64).reshape(-1, 3))
        self._face_source.replace(np.asarray(sources, np.int64))

    # -- arrays --------------------------------------------------------------------------------------
    def point_array(self) -> np.ndarray:
        """(P, 3) the points so far (a view, valid until the next point is added)."""
        return self._points.view()

    def add_point(self, position) -> int:
        """A new point at ``position`` (3,); its id."""
        return self.add_points(np.asarray(position, np.float64).reshape(1, 3))

    def add_points(self, positions) -> int:
        """New points at ``positions`` (k, 3); the id of the first (the others follow)."""
        return self._add_points(positions, np.full(len(positions), NEW_POINT, np.int64))

    def _add_points(self, positions, welded) -> int:
        self._point_welded.extend(welded)
        return self._points.extend(positions)

    def face_points(self) -> np.ndarray:
        """(F, 3) the faces' corners as point ids."""
        return self.row_point[self.faces]


@kernel((I1, I2, F1), cost=0.4)
def descriptions(vertex, parents, t):
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
            for s in range(SOURCES):
                src[r, s] = vertex[r]
            coef[r, 0] = 1.0
            continue
        if t[r] == 0.0 or t[r] == 1.0:        # a copy (a wall's row at a rim's point): bit for bit, so that
            p = parents[r, 0] if t[r] == 0.0 else parents[r, 1]     # a posed drill places both alike
            for s in range(SOURCES):
                src[r, s], coef[r, s] = src[p, s], coef[p, s]
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


@kernel((I1, I2, F1, I2, F2, I1), cost=0.4)
def row_skins(vertex, parents, t, joints, weights, wanted):
    """The joints and weights (k, 4) of the rows ``wanted`` (k,), made for every row: an input row's
    (``vertex[r]`` >= 0) its vertex's; a new row's the blend (1 - t[r]) of row parents[r, 0]'s and t[r]
    of row parents[r, 1]'s (earlier rows: two rim rows for a wall's), the 4 largest kept and
    renormalised, largest first, unused slots bone 0 with weight 0 (``new_vertices.blend_weight_rows``'
    layout); a copy's (t 0 or 1) its parent's."""
    rows = vertex.shape[0]
    out_j, out_w = np.zeros((rows, 4), np.int64), np.zeros((rows, 4))
    bones, values = np.empty(8, np.int64), np.empty(8)
    for r in range(rows):
        if vertex[r] >= 0 or t[r] == 0.0 or t[r] == 1.0:
            row_j, row_w = (joints, weights) if vertex[r] >= 0 else (out_j, out_w)
            v = vertex[r] if vertex[r] >= 0 else parents[r, 0] if t[r] == 0.0 else parents[r, 1]
            for s in range(4):
                out_j[r, s], out_w[r, s] = row_j[v, s], row_w[v, s]
            continue
        count = 0
        for side in range(2):
            p, scale = parents[r, side], t[r] if side == 1 else 1.0 - t[r]
            for s in range(4):
                if out_w[p, s] > 0.0:
                    count = accumulate(bones, values, count, out_j[p, s], scale * out_w[p, s])
        kept = min(4, count)
        total = largest_first(bones, values, count, kept)
        for s in range(kept):
            out_j[r, s], out_w[r, s] = bones[s], values[s] / total
    return _rows_at(out_j, wanted), _rows_at(out_w, wanted)


@kernel((I1, I2, F1, F2, i8, I1), cost=0.3)
def row_values(vertex, parents, t, values, rule, wanted):
    """The rows (k, c) of a per-vertex array ``values`` (n, c) for the rows ``wanted`` (k,), made for
    every row: an input row's its vertex's; a new row's made from its parents' (earlier rows) by
    ``rule`` (``new_vertices.attribute_rule``): LINEAR (1 - t) a + t b, UNIT that at unit length (zero
    stays zero), DOMINANT the parent with the larger share (the first on a tie); a copy's (t 0 or 1)
    its parent's."""
    rows, c = vertex.shape[0], values.shape[1]
    out = np.empty((rows, c))
    for r in range(rows):
        if vertex[r] >= 0:
            for q in range(c):
                out[r, q] = values[vertex[r], q]
            continue
        a, b, w = parents[r, 0], parents[r, 1], t[r]
        if w == 0.0 or w == 1.0 or rule == DOMINANT:
            p = a if w <= 0.5 else b
            for q in range(c):
                out[r, q] = out[p, q]
            continue
        length = 0.0
        for q in range(c):
            out[r, q] = (1.0 - w) * out[a, q] + w * out[b, q]
            length += out[r, q] * out[r, q]
        if rule == UNIT and length > 0.0:
            inverse = 1.0 / math.sqrt(length)
            for q in range(c):
                out[r, q] *= inverse
    return _rows_at(out, wanted)


@helper
def _rows_at(values, rows):
    """(k, c) the rows ``rows`` (k,) of ``values`` (R, c), a new array (``gather.gather_rows``)."""
    out = np.empty((rows.shape[0], values.shape[1]), values.dtype)
    gather_rows(values, rows, out)
    return out


@helper
def new_rows_and_points(corners, welded, row_of, point_of, first_row, first_point):
    """The rows and points that faces with ``corners`` (k, 3) (input vertices) add to a patch, in the
    order the corners come: ``row_of`` (n,) and ``point_of`` (w,) (-1: none yet) get the new ids (rows
    from ``first_row``, points from ``first_point``) in place. Returns the new rows' vertices (v,), their
    points (v,), and the first vertex (p,) of each new point (``welded`` (n,) the welded id of each
    vertex)."""
    flat = corners.ravel()
    vertices, vertex_points, point_vertices = np.empty(flat.size, np.int64), np.empty(flat.size, np.int64), \
        np.empty(flat.size, np.int64)
    rows = points = 0
    for v in flat:
        if row_of[v] >= 0:
            continue
        row_of[v] = first_row + rows
        w = welded[v]
        if point_of[w] < 0:
            point_of[w] = first_point + points
            point_vertices[points] = v
            points += 1
        vertices[rows], vertex_points[rows] = v, point_of[w]
        rows += 1
    return vertices[:rows].copy(), vertex_points[:rows].copy(), point_vertices[:points].copy()


@helper
def put_face(out, made_from, count, f, a, b, c):
    """Write face (a, b, c) made from face f at row ``count`` of ``out`` (k, 3) and ``made_from`` (k,);
    the next row."""
    out[count, 0], out[count, 1], out[count, 2] = a, b, c
    made_from[count] = f
    return count + 1


@helper
def squared_distance(points, a, b):
    """The squared distance between rows a and b of ``points`` (P, 3)."""
    return (points[a, 0] - points[b, 0]) ** 2 + (points[a, 1] - points[b, 1]) ** 2 + (points[a, 2] - points[b, 2]) ** 2
