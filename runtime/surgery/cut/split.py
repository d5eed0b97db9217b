"""Steps 2-4 of a cut: the side of every welded vertex, the faces of both halves, and the new
vertices on crossed edges."""
import math
from typing import NamedTuple

import numpy as np
from numba import types

from ..._shared.jit import helper, kernel, record, F1, F2, I1, I2, S1, f8
from ..._shared.memory import recycled_empty
from ...generated.kernels import plane_from_points, point_plane_distance, segment_plane


class Split(NamedTuple):
    """The faces of both halves and the new vertices on crossed edges (``split_halves``).

    pos_faces (mp, 3), neg_faces (mn, 3) int64 in output numbering: original vertex v -> its rank
        among the half's originals, new vertex j -> the half's original count + j
    pos_src (np,), neg_src (nn,) int64 the original vertices each half keeps, in order
    new_lo, new_hi (k,) int64 the new vertices' edge ends (canonical: lower welded id first)
    new_t (k,) float64 edge parameter from new_lo ; new_point (k, 3) float64 cut-space positions
    """

    pos_faces: np.ndarray
    neg_faces: np.ndarray
    pos_src: np.ndarray
    neg_src: np.ndarray
    new_lo: np.ndarray
    new_hi: np.ndarray
    new_t: np.ndarray
    new_point: np.ndarray


@kernel((F1, F2, I1, I1, f8, F1, S1, S1), cost=0.4)
def _classify(plane, positions, representative, welded, rel_tol, distance, welded_sign, sign):
    """Step 2: the side of every welded vertex, +1, -1, or 0 on the plane (within ``rel_tol`` of the
    bounding-box diagonal), written into ``welded_sign`` (w,) int8, and into ``sign`` (n,) int8 for
    each of its vertices (the faces' corners then need no welded id).

    plane (4,) float64 ; positions (n, 3) float64 ; representative (w,) int64 ; welded (n,) int64 ;
    distance (w,) float64, written: the signed distances
    returns the absolute tolerance and the bounding-box diagonal
    """
    w = representative.shape[0]
    # (the box in scalars, which stay in registers; an array's elements are stored at every step)
    lo_x = lo_y = lo_z = np.inf
    hi_x = hi_y = hi_z = -np.inf
    for i in range(w):
        r = representative[i]
        distance[i] = point_plane_distance(plane, positions[r])
        lo_x, hi_x = min(lo_x, positions[r, 0]), max(hi_x, positions[r, 0])
        lo_y, hi_y = min(lo_y, positions[r, 1]), max(hi_y, positions[r, 1])
        lo_z, hi_z = min(lo_z, positions[r, 2]), max(hi_z, positions[r, 2])
    diag = math.sqrt((hi_x - lo_x) ** 2 + (hi_y - lo_y) ** 2 + (hi_z - lo_z) ** 2)
    tol = rel_tol * diag
    for i in range(w):
        d = distance[i]
        welded_sign[i] = 1 if d > tol else (-1 if d < -tol else 0)
    for v in range(welded.shape[0]):
        sign[v] = welded_sign[welded[v]]
    return tol, diag


@helper
def _put(out, row, a, b, c):
    out[row, 0] = a
    out[row, 1] = b
    out[row, 2] = c


class Scratch(NamedTuple):
    """A cut's working arrays (``scratch``), filled by ``_classify`` and ``_sides`` and read by ``_fill``;
    ``_sides`` leaves ``used`` all 0 and ``_fill`` ``new_of_edge`` all -1 again, as ``scratch`` makes
    them: a later cut of the same rig reuses them.

    referenced (n,) uint8: 1 where a face uses the vertex (the mesh's, set once) ;
    distance (w,) float64: the signed distance of each welded vertex to the plane ;
    welded_sign (w,) int8: the side of each welded vertex (+1, -1, 0 on the plane) ; sign (n,) int8:
    the side of each vertex (its welded vertex's) ; side (m,) int8: +1 / -1 the face lies on that
    side, 0 it is split ; used (n,) uint8: bit 1 the vertex is kept in the positive half, bit 2 in the
    negative one ; new_of_edge (u,) int64: the new vertex on each vertex edge, -1 for none ;
    edge_of_new (u,) int64: the vertex edge of each new vertex (its first k rows) ; pos_map, neg_map
    (n,) int64: each vertex's rank among the half's originals ; pos_src, neg_src (n,) int64: the
    originals each half keeps, in order (their first np, nn rows: ``Split.pos_src``, ``neg_src``)
    """

    referenced: np.ndarray
    distance: np.ndarray
    welded_sign: np.ndarray
    sign: np.ndarray
    side: np.ndarray
    used: np.ndarray
    new_of_edge: np.ndarray
    edge_of_new: np.ndarray
    pos_map: np.ndarray
    neg_map: np.ndarray
    pos_src: np.ndarray
    neg_src: np.ndarray


def scratch(faces, topo) -> Scratch:
    """New working arrays for a cut of the mesh of these faces (m, 3) int64 and ``Topology``."""
    n, m, u, w = len(topo.welded), len(faces), len(topo.vertex_edges), len(topo.representative)
    referenced = np.zeros(n, np.uint8)
    referenced[faces] = 1
    # (edge_of_new: only its first rows are ever written, so only their pages are ever mapped)
    return Scratch(referenced, np.empty(w), np.empty(w, np.int8), np.empty(n, np.int8), np.empty(m, np.int8),
                   np.zeros(n, np.uint8), np.full(u, -1, np.int64), np.empty(u, np.int64),
                   *(np.empty(n, np.int64) for _ in range(4)))


#: the numba types of the arrays of ``rig_topology`` a split reads (welded, representative,
#: face_vertex_edges, vertex_edges), of a ``Scratch`` and of a ``Split``
CUT_TOPOLOGY = record(I1, I1, I2, I2)
SCRATCH = record(types.uint8[::1], F1, S1, S1, S1, types.uint8[::1], I1, I1, I1, I1, I1, I1)
SPLIT = record(I2, I2, I1, I1, I1, I1, F1, F2)


def split_halves(plane, positions, faces, topo, work: Scratch) -> Split:
    """Steps 3-4: classify the faces, number the new vertices, and write both halves' faces.

    plane (4,) float64 ; positions (n, 3) float64 cut-space positions ; faces (m, 3) int64 ;
    topo : Topology (``rig_topology``) ; work : Scratch, its signs from ``_classify``
    returns the ``Split``: its ``pos_src`` and ``neg_src`` are rows of ``work`` (read them while it is
    held), the other arrays its own

    The faces' arrays are made here (``recycled_empty``) once the first pass has counted them, and
    filled by the second: the halves' rigs hold them as they are, without a copy (see ``assemble``).
    """
    arrays = (topo.welded, topo.representative, topo.face_vertex_edges, topo.vertex_edges)
    n_new, m_pos, m_neg, n_pos, n_neg = _sides(plane, positions, faces, arrays, tuple(work))
    out = Split(recycled_empty((m_pos, 3), np.int64), recycled_empty((m_neg, 3), np.int64), work.pos_src[:n_pos],
                work.neg_src[:n_neg], np.empty(n_new, np.int64), np.empty(n_new, np.int64), np.empty(n_new),
                np.empty((n_new, 3)))
    _fill(plane, positions, faces, arrays, tuple(work), tuple(out))
    return out


@kernel((F1, F2, I2, CUT_TOPOLOGY, SCRATCH), cost=1.2)
def _sides(plane, positions, faces, topo, work):
    """First pass: the side of each face, the vertices each half keeps (``pos_src``, ``neg_src``) and
    their ranks, the numbering of the new vertices (in face order).

    returns the counts (new vertices, positive faces, negative faces, positive originals, negative
    originals)
    """
    welded, representative, face_vertex_edges, vertex_edges = topo
    referenced, _, _, sign, side, used, new_of_edge, edge_of_new, pos_map, neg_map, pos_src, neg_src = work
    n = positions.shape[0]
    m = faces.shape[0]
    n_new = 0
    m_pos = 0
    m_neg = 0
    for f in range(m):
        s0 = sign[faces[f, 0]]
        s1 = sign[faces[f, 1]]
        s2 = sign[faces[f, 2]]
        if s0 == s1 and s1 == s2 and s0 != 0:          # most faces: all corners on one side
            side[f] = s0
            if s0 > 0:
                m_pos += 1
            else:
                m_neg += 1
            continue
        has_pos = s0 > 0 or s1 > 0 or s2 > 0
        has_neg = s0 < 0 or s1 < 0 or s2 < 0
        if has_pos and has_neg:
            side[f] = 0
            for k in range(3):
                v = faces[f, k]
                sk = sign[v]
                if sk == 0:
                    used[v] = 3
                if sk * sign[faces[f, (k + 1) % 3]] < 0:
                    e = face_vertex_edges[f, k]
                    if new_of_edge[e] < 0:
                        new_of_edge[e] = n_new
                        n_new += 1
            if s0 == 0 or s1 == 0 or s2 == 0:          # one triangle on each side
                m_pos += 1
                m_neg += 1
            elif s0 + s1 + s2 < 0:                     # lone positive corner: 1 positive, 2 negative
                m_pos += 1
                m_neg += 2
            else:
                m_pos += 2
                m_neg += 1
            continue
        if has_pos:
            s = 1
        elif has_neg:
            s = -1
        else:
            # In the plane: it bounds the part its normal points away from. (A degenerate face has
            # no normal: NaN compares false and it goes to the positive side.)
            own = plane_from_points(positions[faces[f, 0]], positions[faces[f, 1]], positions[faces[f, 2]])
            along = own[0] * plane[0] + own[1] * plane[1] + own[2] * plane[2]
            s = -1 if along > 0 else 1
        side[f] = s
        if s0 == 0 or s1 == 0 or s2 == 0:
            bit = 1 if s > 0 else 2
            for k in range(3):
                v = faces[f, k]
                if sign[v] == 0:
                    used[v] |= bit
        if s > 0:
            m_pos += 1
        else:
            m_neg += 1

    n_pos = 0
    n_neg = 0
    # A vertex off the plane is kept by the half on its side when some face uses it (every face with
    # a corner on the positive side is positive or split, and either keeps that corner there); the
    # face loop above marked only the vertices on the plane. ``used`` is left all 0 again.
    for v in range(n):
        kept = used[v]
        if referenced[v]:
            sv = sign[v]
            if sv > 0:
                kept = 1
            elif sv < 0:
                kept = 2
        pos_map[v] = n_pos
        neg_map[v] = n_neg
        if kept & 1:
            pos_src[n_pos] = v
            n_pos += 1
        if kept & 2:
            neg_src[n_neg] = v
            n_neg += 1
        used[v] = 0
    return n_new, m_pos, m_neg, n_pos, n_neg


@helper
def _new_vertex(plane, positions, welded, representative, vertex_edges, e, j, new_lo, new_hi, new_t, new_point):
    """New vertex j, on vertex edge e. Every copy of a welded edge gets the point computed from the
    welded endpoints in the same order, so all copies land at bitwise the same position."""
    va = vertex_edges[e, 0]
    vb = vertex_edges[e, 1]
    if welded[va] > welded[vb]:
        va, vb = vb, va
    r = segment_plane(plane, positions[representative[welded[va]]], positions[representative[welded[vb]]])
    new_lo[j] = va
    new_hi[j] = vb
    new_t[j] = r[0]
    new_point[j, 0] = r[1]
    new_point[j, 1] = r[2]
    new_point[j, 2] = r[3]


@kernel((F1, F2, I2, CUT_TOPOLOGY, SCRATCH, SPLIT), cost=1.2)
def _fill(plane, positions, faces, topo, work, out):
    """Second pass: write the fields of ``Split`` (arrays of the sizes ``_sides`` counted; its
    ``pos_src`` and ``neg_src`` are ``_sides``'), and leave ``work.new_of_edge`` as ``scratch`` made it.

    Faces refer to output rows: original vertex v -> map[v] (its rank among the half's original
    vertices), new vertex j -> n_half_originals + j.
    """
    welded, representative, face_vertex_edges, vertex_edges = topo
    _, _, _, sign, side, _, new_of_edge, edge_of_new, pos_map, neg_map, _, _ = work
    pos_faces, neg_faces, pos_src, neg_src, new_lo, new_hi, new_t, new_point = out
    m = faces.shape[0]
    n_pos = pos_src.shape[0]
    n_neg = neg_src.shape[0]

    # Faces of both halves, in output numbering.
    ip = np.int64(0)           # np.int64, not a literal: see tear/records.py's note on literals
    ineg = np.int64(0)
    n_done = np.int64(0)
    for f in range(m):
        s = side[f]
        if s > 0:
            _put(pos_faces, ip, pos_map[faces[f, 0]], pos_map[faces[f, 1]], pos_map[faces[f, 2]])
            ip += 1
            continue
        if s < 0:
            _put(neg_faces, ineg, neg_map[faces[f, 0]], neg_map[faces[f, 1]], neg_map[faces[f, 2]])
            ineg += 1
            continue
        # New vertices where the first pass numbered them: at the first face crossing their edge,
        # in order (so only the crossed faces are visited, not every edge).
        for k in range(3):
            if sign[faces[f, k]] * sign[faces[f, (k + 1) % 3]] < 0:
                e = face_vertex_edges[f, k]
                j = new_of_edge[e]
                if j == n_done:
                    _new_vertex(plane, positions, welded, representative, vertex_edges, e, j, new_lo, new_hi,
                                new_t, new_point)
                    edge_of_new[j] = e
                    n_done += 1
        zero = -1
        for k in range(3):
            if sign[faces[f, k]] == 0:
                zero = k
        if zero >= 0:
            # corners z (on the plane), p, q on opposite sides; x on edge p-q
            p_k = (zero + 1) % 3
            q_k = (zero + 2) % 3
            z, p, q = faces[f, zero], faces[f, p_k], faces[f, q_k]
            x = new_of_edge[face_vertex_edges[f, p_k]]
            if sign[faces[f, p_k]] > 0:
                _put(pos_faces, ip, pos_map[z], pos_map[p], n_pos + x)
                _put(neg_faces, ineg, neg_map[z], n_neg + x, neg_map[q])
            else:
                _put(neg_faces, ineg, neg_map[z], neg_map[p], n_neg + x)
                _put(pos_faces, ip, pos_map[z], n_pos + x, pos_map[q])
            ip += 1
            ineg += 1
            continue
        # the lone corner a (its sign differs from b's and c's); x_ab, x_ca on its two edges
        s0 = sign[faces[f, 0]]
        s1 = sign[faces[f, 1]]
        lone = 0 if s0 != s1 and s1 == sign[faces[f, 2]] else (1 if s0 == sign[faces[f, 2]] else 2)
        b_k = (lone + 1) % 3
        c_k = (lone + 2) % 3
        a, b, c = faces[f, lone], faces[f, b_k], faces[f, c_k]
        xab = new_of_edge[face_vertex_edges[f, lone]]
        xca = new_of_edge[face_vertex_edges[f, c_k]]
        # the quad xab, b, c, xca takes its shorter diagonal (better-shaped triangles)
        d1 = 0.0
        d2 = 0.0
        for i in range(3):
            d1 += (new_point[xab, i] - positions[c, i]) ** 2
            d2 += (positions[b, i] - new_point[xca, i]) ** 2
        if sign[faces[f, lone]] > 0:
            _put(pos_faces, ip, pos_map[a], n_pos + xab, n_pos + xca)
            ip += 1
            if d1 <= d2:
                _put(neg_faces, ineg, n_neg + xab, neg_map[b], neg_map[c])
                _put(neg_faces, ineg + 1, n_neg + xab, neg_map[c], n_neg + xca)
            else:
                _put(neg_faces, ineg, n_neg + xab, neg_map[b], n_neg + xca)
                _put(neg_faces, ineg + 1, neg_map[b], neg_map[c], n_neg + xca)
            ineg += 2
        else:
            _put(neg_faces, ineg, neg_map[a], n_neg + xab, n_neg + xca)
            ineg += 1
            if d1 <= d2:
                _put(pos_faces, ip, n_pos + xab, pos_map[b], pos_map[c])
                _put(pos_faces, ip + 1, n_pos + xab, pos_map[c], n_pos + xca)
            else:
                _put(pos_faces, ip, n_pos + xab, pos_map[b], n_pos + xca)
                _put(pos_faces, ip + 1, pos_map[b], pos_map[c], n_pos + xca)
            ip += 2
    for j in range(n_done):
        new_of_edge[edge_of_new[j]] = -1
