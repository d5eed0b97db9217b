"""The faces around a drill's rim, refined until the rim can be drawn finely: longest-edge bisection.

A hole is round only if the mesh has vertices close together where the bit's surface crosses it; a real
model's faces are often larger than the hole. So before the rim is placed, every face that the bit's
surface passes through (part of it inside the bit, part outside: ``bit.near_faces``) and whose longest
edge is longer than ``step`` is bisected on its longest edge, and a face that shares a bisected edge is bisected too (on its
longest edge first, then on the shared one: Rivara's longest-edge bisection, which keeps the angles of
the refined faces bounded and leaves no vertex in the middle of a neighbour's edge). Rounds repeat until
no face the surface passes through is longer than ``step``: the rim's edges are then at most ``step``
long, and a face left outside the bit reaches into it by no more than such an edge's sagitta.

The working mesh is the part of the surface refined so far (``Patch``): its faces are rows of the
vertex table (attribute-split copies kept apart: a seam edge bisected gets one new row per copy, all at
one position), its points the welded vertices (one position per place). Edges are welded: the bisection
of a seam edge is seen from both sides. A new row is described as a convex combination of the corners
of the input face it lies in (``src``, ``coef``), from which its weights and attributes are made.
"""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F1, I1, I2, kernel
from ...errors import InternalError
from .bit import near_faces

#: refinement rounds before giving up (each halves the faces near the rim: 2^60 is beyond any model)
MAX_ROUNDS = 60
#: input vertices a new vertex is described by at most: 3 in a face, 6 on a wall (between two rims)
SOURCES = 6


class Patch:
    """The refined part of a mesh around a bit.

    points : list of (3,) float64, one position per welded vertex of the patch
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
        self.points, self.point_of, self.point_welded = [], {}, {}
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
                p = self.point_of[w] = len(self.points)
                self.points.append(self.positions[v])
                self.point_welded[p] = w
            r = self.row_of[v] = len(self.row_point)
            self.row_point.append(p)
            self.row_vertex.append(v)
            self.row_parents.append((r, r, 0.0))
            self.input_rows.append(r)
        return r

    def take_all(self, faces) -> None:
        """Add the input faces ``faces`` (k,) to the patch (none taken yet: the first ones)."""
        corners = self.mesh_faces[faces]
        for v in np.unique(corners).tolist():
            self.row(v)
        row_of = self.row_of
        self.faces.extend([[row_of[a], row_of[b], row_of[c]] for a, b, c in corners.tolist()])
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
            p = self.midpoints[point_key] = len(self.points)
            self.points.append(0.5 * (self.points[point_key[0]] + self.points[point_key[1]]) if place is None
                               else place(*point_key))
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
        return np.array(self.points, dtype=np.float64).reshape(-1, 3)

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
                c = scale * coef[p, s]
                if c == 0.0:
                    continue
                found = False
                for q in range(count):
                    if keys[q] == src[p, s]:
                        values[q] += c
                        found = True
                        break
                if not found:
                    keys[count], values[count] = src[p, s], c
                    count += 1
        kept = min(count, SOURCES)
        total = 0.0
        for slot in range(kept):                 # selection of the largest (ties: the first met)
            best = slot
            for q in range(slot + 1, count):
                if values[q] > values[best]:
                    best = q
            keys[slot], keys[best] = keys[best], keys[slot]
            values[slot], values[best] = values[best], values[slot]
            total += values[slot]
        for slot in range(SOURCES):
            src[r, slot] = keys[slot] if slot < kept else keys[0]
            coef[r, slot] = values[slot] / total if slot < kept else 0.0
    return src, coef


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
        _bisect(patch, marked)
    raise InternalError(f"the faces near the bit did not become shorter than {step:g} in {MAX_ROUNDS} rounds")


def _close(patch: Patch, marked) -> np.ndarray:
    """The edge codes ``marked`` and the longest edge of every face that has a marked edge, until none
    is added; input faces beyond the patch on a marked input edge join it first."""
    topology, welded = patch.topology, patch.point_welded
    seen = set()
    while True:
        grown = False
        for a, b in _edge_pairs(marked):
            if (a, b) in seen:
                continue
            seen.add((a, b))
            if a in welded and b in welded:
                for face in _input_faces(topology, welded[a], welded[b]):
                    grown |= patch.take(int(face))
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


def _bisect(patch: Patch, marked, place=None) -> None:
    """Split every face with marked edges (codes): on its longest edge where it is marked (``_close``
    sees to it), then each half on the marked edge it keeps; ``place`` as for ``Patch.midpoint_row``."""
    points, face_points = patch.point_array(), patch.face_points()
    k, _ = _longest(points, face_points)
    split = np.isin(_edge_codes(face_points), marked)
    pairs = _edge_pairs(marked)
    faces, sources = [], []
    for f, (rows, source) in enumerate(zip(patch.faces, patch.face_source)):
        children = _split(patch, rows, int(k[f]), split[f].tolist(), pairs, place) if split[f].any() else (rows,)
        for child in children:
            faces.append(child)
            sources.append(source)
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
