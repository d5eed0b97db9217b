"""Steps 2-4 of a cut: the side of every welded vertex, the faces of both halves, and the new
vertices on crossed edges."""
import math
from typing import NamedTuple

import numpy as np

from ...generated.kernels import plane_from_points, point_plane_distance, segment_plane


class Split(NamedTuple):
    """The faces of both halves and the new vertices on crossed edges (``_split``).

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
from ..._shared.jit import helper, kernel, F1, F2, I1, I2, S1, f8


@kernel((F1, F2, I1, f8), cost=0.4)
def _classify(plane, positions, representative, rel_tol):
    """Signed distance and side of every welded vertex.

    returns sign (w,) int8 (+1, -1, or 0 on the plane), absolute tolerance, bounding-box diagonal
    """
    w = representative.shape[0]
    dist = np.empty(w)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for i in range(w):
        x = positions[representative[i]]
        dist[i] = point_plane_distance(plane, x)
        for c in range(3):
            lo[c] = min(lo[c], x[c])
            hi[c] = max(hi[c], x[c])
    diag = 0.0
    for c in range(3):
        diag += (hi[c] - lo[c]) ** 2
    diag = math.sqrt(diag)
    tol = rel_tol * diag
    sign = np.empty(w, np.int8)
    for i in range(w):
        sign[i] = 1 if dist[i] > tol else (-1 if dist[i] < -tol else 0)
    return sign, tol, diag


@helper
def _put(out, row, a, b, c):
    out[row, 0] = a
    out[row, 1] = b
    out[row, 2] = c


@kernel((F1, F2, I2, I2, I1, I1, S1, I2, I2), cost=2.1)
def _split(plane, positions, faces, wfaces, welded, representative, sign, face_vertex_edges,
           vertex_edges):
    """Classify faces, create the vertices on crossed edges, and write both halves' faces.

    Faces refer to output rows: original vertex v -> map[v] (its rank among the half's original
    vertices), new vertex j -> n_half_originals + j.

    returns the fields of ``Split``
    """
    n = positions.shape[0]
    m = faces.shape[0]
    side = np.empty(m, np.int8)             # +1 / -1: whole face on that side; 0: split
    used = np.zeros(n, np.uint8)            # bit 1: kept in the positive half, bit 2: in the negative
    new_of_edge = np.full(vertex_edges.shape[0], -1, np.int64)
    n_new = 0
    m_pos = 0
    m_neg = 0
    for f in range(m):
        s0 = sign[wfaces[f, 0]]
        s1 = sign[wfaces[f, 1]]
        s2 = sign[wfaces[f, 2]]
        has_pos = s0 > 0 or s1 > 0 or s2 > 0
        has_neg = s0 < 0 or s1 < 0 or s2 < 0
        if has_pos and has_neg:
            side[f] = 0
            for k in range(3):
                sk = sign[wfaces[f, k]]
                v = faces[f, k]
                used[v] |= 1 if sk > 0 else (2 if sk < 0 else 3)
                if sk * sign[wfaces[f, (k + 1) % 3]] < 0:
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
        bit = 1 if s > 0 else 2
        for k in range(3):
            used[faces[f, k]] |= bit
        if s > 0:
            m_pos += 1
        else:
            m_neg += 1

    # Ranks of the kept original vertices in each half.
    pos_map = np.empty(n, np.int64)
    neg_map = np.empty(n, np.int64)
    n_pos = 0
    n_neg = 0
    for v in range(n):
        pos_map[v] = n_pos
        neg_map[v] = n_neg
        n_pos += used[v] & 1
        n_neg += (used[v] >> 1) & 1
    pos_src = np.empty(n_pos, np.int64)
    neg_src = np.empty(n_neg, np.int64)
    for v in range(n):
        if used[v] & 1:
            pos_src[pos_map[v]] = v
        if used[v] & 2:
            neg_src[neg_map[v]] = v

    # New vertices: every copy of a welded edge gets the point computed from the welded endpoints in
    # the same order, so all copies land at bitwise the same position.
    new_lo = np.empty(n_new, np.int64)
    new_hi = np.empty(n_new, np.int64)
    new_t = np.empty(n_new)
    new_point = np.empty((n_new, 3))
    if n_new:
        for e in range(vertex_edges.shape[0]):
            j = new_of_edge[e]
            if j < 0:
                continue
            va = vertex_edges[e, 0]
            vb = vertex_edges[e, 1]
            if welded[va] > welded[vb]:
                va, vb = vb, va
            r = segment_plane(plane, positions[representative[welded[va]]],
                              positions[representative[welded[vb]]])
            new_lo[j] = va
            new_hi[j] = vb
            new_t[j] = r[0]
            new_point[j, 0] = r[1]
            new_point[j, 1] = r[2]
            new_point[j, 2] = r[3]

    # Faces of both halves, in output numbering.
    pos_faces = np.empty((m_pos, 3), np.int64)
    neg_faces = np.empty((m_neg, 3), np.int64)
    ip = np.int64(0)           # np.int64, not a literal: see tear/records.py's note on literals
    ineg = np.int64(0)
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
        zero = -1
        for k in range(3):
            if sign[wfaces[f, k]] == 0:
                zero = k
        if zero >= 0:
            # corners z (on the plane), p, q on opposite sides; x on edge p-q
            p_k = (zero + 1) % 3
            q_k = (zero + 2) % 3
            z, p, q = faces[f, zero], faces[f, p_k], faces[f, q_k]
            x = new_of_edge[face_vertex_edges[f, p_k]]
            if sign[wfaces[f, p_k]] > 0:
                _put(pos_faces, ip, pos_map[z], pos_map[p], n_pos + x)
                _put(neg_faces, ineg, neg_map[z], n_neg + x, neg_map[q])
            else:
                _put(neg_faces, ineg, neg_map[z], neg_map[p], n_neg + x)
                _put(pos_faces, ip, pos_map[z], n_pos + x, pos_map[q])
            ip += 1
            ineg += 1
            continue
        # the lone corner a (its sign differs from b's and c's); x_ab, x_ca on its two edges
        s0 = sign[wfaces[f, 0]]
        s1 = sign[wfaces[f, 1]]
        lone = 0 if s0 != s1 and s1 == sign[wfaces[f, 2]] else (1 if s0 == sign[wfaces[f, 2]] else 2)
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
        if sign[wfaces[f, lone]] > 0:
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
    return pos_faces, neg_faces, pos_src, neg_src, new_lo, new_hi, new_t, new_point
