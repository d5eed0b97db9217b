"""Cut a skinned mesh with a plane into two rigs.

``cut(rig, normal, point, pose=None, cap=False) -> (positive, negative)``

The plane is {x : n·(x − point) = 0}; ``positive`` is the part on the side the normal points to
(signed distance d > 0), ``negative`` the other part. Both keep the full skeleton and clips.

Steps (design.md section 4, "Cut (plane)"):

1. Positions to cut: the stored vertices (``pose=None``), or the skinned positions in ``pose`` (a
   posed cut; ``rig.rest_pose()`` cuts what a viewer shows at rest).
2. Signed distance of every welded vertex to the plane through the generated CGA kernel
   (``point_plane_distance``: up(x)·π); vertices within ``ON_PLANE_TOLERANCE`` times the bounding-box
   diagonal are *on* the plane and belong to both halves (no sliver faces, no duplicate vertices).
3. Faces entirely on one side (on-plane corners allowed) go to that side; a face lying in the plane goes
   to the side its normal points away from (so a closed part stays closed). A face with corners on
   both sides is split into one triangle and a quad (two triangles), or into two triangles when its
   third corner is on the plane; the winding is kept.
4. One new vertex per crossed *vertex edge* (attribute-split copies of a seam edge each get one, with
   their own NORMAL/TEXCOORD_0 interpolated by the edge parameter t), all copies at ONE position computed
   from the *welded* edge (generated ``segment_plane`` on the welded endpoints in a canonical order), so
   the halves have no cracks along seams. Weights: the two endpoint rows interpolated by t (up to 8
   influences), the 4 largest kept and renormalised.
5. A posed cut puts each new vertex on the plane *in that pose*: its posed position is the point of the
   posed edge, and its rest position solves B x = p for its own blended 3x4 map B = Σ w_k A_k (with the
   new weights), starting from the interpolated rest position and refined once; the residual is checked.
6. Each half keeps the original vertices it uses (in their original order, attributes and weights
   bit-for-bit) followed by the new vertices (same order in both halves).
7. ``cap=True`` closes each half: the boundary loops the cut created (welded boundary edges whose ends
   lie on the plane and that were not boundary edges before) are triangulated in the plane (ear clipping;
   a hole, a loop the mesh orients clockwise, is bridged into the smallest outer loop around it, so a
   hollow part gets an annulus), on cap vertices of their own (positions, joints and weights copied from
   the loop vertices, NORMAL along the outward plane normal, TEXCOORD_0 a planar projection), wound so
   that the cap faces outwards. A closed, consistently oriented input whose section does not intersect
   itself gives watertight halves; a self-intersecting section (a crumpled pose) gets overlapping caps.

Conventions and limits: vertices that no face uses are dropped. Attribute-split copies are assumed to
skin alike (same joints and weights, as files store them): a posed cut classifies and places a welded
vertex by its lowest-index copy. A rig is treated as immutable: its welded topology and checked arrays
are cached per rig (``topology.rig_cached``), and its arrays are never written to.

A plane that misses the mesh (no face on one side) returns the whole rig (a copy) on the side it lies
on and an empty rig on the other, with a ``PlaneMissesMeshWarning``: ``(copy, empty)`` when the mesh
is on the positive side, ``(empty, copy)`` when it is on the negative side.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit

from ...errors import InvalidInputError
from ...generated.kernels import (affine_point, plane_from_normal_distance, plane_from_points,
                                point_plane_distance, point_plane_distance_batch, segment_plane)
from ...animation.pose import check_pose
from ...animation.rig import Rig
from ...animation.skinning import skin_affine
from ..new_vertices import blend_weight_rows
from ..topology import Topology, directed_loops, rig_cached, rig_topology, topology

__all__ = ["cut", "cut_details", "CutResult", "PlaneMissesMeshWarning", "ON_PLANE_TOLERANCE",
           "PLACEMENT_TOLERANCE"]

#: |d| <= this times the bounding-box diagonal: the vertex is on the plane (in both halves)
ON_PLANE_TOLERANCE = 1e-10
#: a posed cut's new vertex whose skinned rest position misses its posed target by more than this times
#: the diagonal is reported (a warning): its blended transform is singular or nearly so
PLACEMENT_TOLERANCE = 1e-9
#: values of ``CutResult.sources``: vertices created on crossed edges, and cap vertices
NEW_VERTEX, CAP_VERTEX = -1, -2


class PlaneMissesMeshWarning(UserWarning):
    """The cutting plane does not cross the mesh: one half is empty."""


@dataclass(frozen=True, eq=False)
class CutResult:
    """A cut with the bookkeeping that relates the halves to the input.

    positive, negative : Rig, the parts with d > 0 and d < 0 (on-plane vertices in both)
    sources : (Rig vertex -> input vertex) per half: ``(n_pos,)`` and ``(n_neg,)`` int64 arrays holding
        the input vertex of each output vertex, ``NEW_VERTEX`` (-1) for a vertex created on a crossed edge
        and ``CAP_VERTEX`` (-2) for a cap vertex
    edge_vertices : (k, 2) int64, the input vertices (a, b) of the edge of each new vertex
    edge_t : (k,) float64, its parameter: cut-space position (1 − t) x_a + t x_b
    new_positions : (k, 3) float64, the new vertices in the space that was cut (rest, or posed)
    first_new : (2,) int, index of the first new vertex in each half (new vertex j is row
        ``first_new[h] + j`` of half h)
    plane : (4,) float64, the dual plane n̂ + d e∞ that was cut with
    tolerance : float, the on-plane tolerance used (absolute, in cut-space units)
    residual : float, the largest |skinned new vertex − its posed target| (0 for a rest cut)
    """

    positive: Rig
    negative: Rig
    sources: tuple
    edge_vertices: np.ndarray
    edge_t: np.ndarray
    new_positions: np.ndarray
    first_new: tuple
    plane: np.ndarray
    tolerance: float
    residual: float


# ---- kernels ------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy")
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _put(out, row, a, b, c):
    out[row, 0] = a
    out[row, 1] = b
    out[row, 2] = c


@njit(cache=True, nogil=True, error_model="numpy")
def _split(plane, positions, faces, wfaces, welded, representative, sign, face_vertex_edges,
           vertex_edges):
    """Classify faces, create the vertices on crossed edges, and write both halves' faces.

    Faces refer to output rows: original vertex v -> map[v] (its rank among the half's original
    vertices), new vertex j -> n_half_originals + j.

    returns pos_faces (mp, 3), neg_faces (mn, 3), pos_src (np,), neg_src (nn,) original vertices kept,
        new_lo, new_hi (k,) the new vertices' edge endpoints (canonical: lower welded id first),
        new_t (k,) edge parameter from new_lo, new_point (k, 3) cut-space positions
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
    ip = np.int64(0)           # np.int64, not a literal: see tear.py's note on literals
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _solve3(m, r):
    """x with L x = r for the linear part L (3x3) of a row-major 3x4 map ``m`` (12,), by Cramer's rule;
    returns (x0, x1, x2, det)."""
    a, b, c = m[0], m[1], m[2]
    d, e, f = m[4], m[5], m[6]
    g, h, i = m[8], m[9], m[10]
    c0 = e * i - f * h
    c1 = f * g - d * i
    c2 = d * h - e * g
    det = a * c0 + b * c1 + c * c2
    if det == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    inv = 1.0 / det
    x0 = (r[0] * c0 + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) * inv
    x1 = (r[0] * c1 + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) * inv
    x2 = (r[0] * c2 + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) * inv
    return x0, x1, x2, det


@njit(cache=True, nogil=True, error_model="numpy")
def _place_in_rest(target, guess, joints, weights, affines):
    """Rest positions x with Σ_k w_k A_k(x) = target for each new vertex (its own blended 3x4 map).

    The solve is relative to ``guess`` (the interpolated rest position, close to the answer) and
    repeated once on the residual, so the error is that of one affine map evaluation.

    returns rest (k, 3), residual (k,) |B x − target|, singular (k,) bool (kept at the guess)
    """
    k = target.shape[0]
    rest = np.empty((k, 3))
    residual = np.empty(k)
    singular = np.zeros(k, np.bool_)
    blend = np.empty(12)
    r = np.empty(3)
    for i in range(k):
        blend[:] = 0.0
        for s in range(joints.shape[1]):
            w = weights[i, s]
            if w != 0.0:
                a = affines[joints[i, s]]
                for c in range(12):
                    blend[c] += w * a[c]
        x = guess[i].copy()
        for _ in range(2):
            y = affine_point(blend, x)
            r[0] = target[i, 0] - y[0]
            r[1] = target[i, 1] - y[1]
            r[2] = target[i, 2] - y[2]
            d0, d1, d2, det = _solve3(blend, r)
            if det == 0.0 or not (math.isfinite(d0) and math.isfinite(d1) and math.isfinite(d2)):
                singular[i] = True
                break
            x[0] += d0
            x[1] += d1
            x[2] += d2
        y = affine_point(blend, x)
        residual[i] = math.sqrt((target[i, 0] - y[0]) ** 2 + (target[i, 1] - y[1]) ** 2
                                + (target[i, 2] - y[2]) ** 2)
        rest[i, 0], rest[i, 1], rest[i, 2] = x[0], x[1], x[2]
    return rest, residual, singular


# ---- argument checks ----------------------------------------------------------------------------------
def _vector(value, name) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be 3 numbers, got {value!r}: {exc}") from None
    if arr.shape != (3,):
        raise InvalidInputError(f"{name} must have shape (3,), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InvalidInputError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def _mesh(rig):
    """The rig's arrays as the kernels need them, checked once per rig (cached with its topology)."""
    if not isinstance(rig, Rig):
        raise InvalidInputError(f"rig must be a cgaskin.Rig, got {type(rig).__name__}")
    return rig_cached(rig, "cut.mesh", _checked_mesh)


def _checked_mesh(rig):
    """(vertices (n, 3) float64, joints (n, 4) int64, weights (n, 4) float64), C-contiguous, checked;
    no copy where the rig's arrays already are so."""
    vertices = np.ascontiguousarray(rig.vertices, dtype=np.float64)
    faces = np.asarray(rig.faces)
    joints = np.asarray(rig.joints)
    weights = np.asarray(rig.weights)
    n = len(vertices)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidInputError(f"rig.vertices must have shape (n, 3), got {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and faces.dtype.kind not in "iu"):
        raise InvalidInputError(f"rig.faces must be an (m, 3) integer array, got {faces.shape} {faces.dtype}")
    if len(faces) == 0:
        raise InvalidInputError("the rig has no faces: there is nothing to cut")
    if not np.isfinite(vertices).all():
        raise InvalidInputError("rig.vertices hold non-finite values (NaN or inf)")
    if joints.ndim != 2 or joints.shape != weights.shape or len(joints) != n or not 1 <= joints.shape[1] <= 4:
        raise InvalidInputError(f"rig.joints {joints.shape} and rig.weights {weights.shape} must both "
                                f"have shape ({n}, 4)")
    if joints.dtype.kind not in "iu":
        raise InvalidInputError(f"rig.joints must hold integers, got {joints.dtype}")
    weights = np.ascontiguousarray(weights, dtype=np.float64)
    joints = np.ascontiguousarray(joints, dtype=np.int64)
    if joints.shape[1] < 4:                      # pad to 4 influences (zero weights change nothing)
        pad = 4 - joints.shape[1]
        joints = np.concatenate([joints, np.zeros((n, pad), np.int64)], axis=1)
        weights = np.concatenate([weights, np.zeros((n, pad))], axis=1)
    if not np.isfinite(weights).all() or (weights < 0).any():
        raise InvalidInputError("rig.weights must be finite and >= 0")
    n_bones = rig.skeleton.n_bones
    if joints.size and (joints.min() < 0 or joints.max() >= n_bones):
        raise InvalidInputError(f"rig.joints must index the {n_bones} bones")
    for name, values in rig.attributes.items():
        if len(np.asarray(values)) != n:
            raise InvalidInputError(f"attribute {name!r} has {len(values)} rows for {n} vertices")
    return vertices, joints, weights


def _plane(normal, point) -> np.ndarray:
    n = _vector(normal, "normal")
    p = _vector(point, "point")
    scale = np.abs(n).max()
    if scale == 0.0:
        raise InvalidInputError("normal must not be the zero vector")
    n = n / scale                  # the kernel normalises; pre-scaling keeps n·n from under/overflowing
    return np.array(plane_from_normal_distance(n, float(n @ p)))


# ---- assembly -----------------------------------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy")
def _lerp_rows(values, lo, hi, t, unit):
    """Rows (k, c) of new vertices: (1 − t) values[lo] + t values[hi]; renormalised when ``unit``
    (normals), a zero result staying zero."""
    k = lo.shape[0]
    c = values.shape[1]
    out = np.empty((k, c))
    for i in range(k):
        s = 0.0
        for j in range(c):
            x = (1.0 - t[i]) * values[lo[i], j] + t[i] * values[hi[i], j]
            out[i, j] = x
            s += x * x
        if unit and s > 0.0:
            inv = 1.0 / math.sqrt(s)
            for j in range(c):
                out[i, j] *= inv
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _assemble(values, pos_src, neg_src, extra):
    """Both halves' rows of one per-vertex array: values[src] followed by ``extra`` (the new vertices)."""
    c = values.shape[1]
    k = extra.shape[0]
    halves = []
    for src in (pos_src, neg_src):
        n = src.shape[0]
        out = np.empty((n + k, c), values.dtype)
        for i in range(n):
            for j in range(c):
                out[i, j] = values[src[i], j]
        for i in range(k):
            for j in range(c):
                out[n + i, j] = extra[i, j]
        halves.append(out)
    return halves[0], halves[1]


def _split_arrays(rig, vertices, joints, weights, pos_src, neg_src, new_lo, new_hi, new_t, new_rest,
                  new_joints, new_weights):
    """Per-vertex arrays of both halves: (vertices, joints, weights, attributes) for each."""
    out = [_assemble(vertices, pos_src, neg_src, new_rest), _assemble(joints, pos_src, neg_src, new_joints),
           _assemble(weights, pos_src, neg_src, new_weights)]
    attributes = ({}, {})
    for key, values in rig.attributes.items():
        values = np.asarray(values)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        if flat.dtype.kind != "f":
            flat = flat.astype(np.float64)
        if key.startswith("_"):
            # application-specific data (e.g. the tear's "_TEAR" labels) may not be interpolable:
            # a new vertex takes the row of the nearer edge end
            new = np.where((np.asarray(new_t) < 0.5)[:, None], flat[new_lo], flat[new_hi])
        else:
            unit = key == "NORMAL" and flat.shape[1] == 3
            new = _lerp_rows(flat, new_lo, new_hi, new_t, unit).astype(flat.dtype, copy=False)
        for h, rows in enumerate(_assemble(flat, pos_src, neg_src, new)):
            attributes[h][key] = rows.reshape((len(rows),) + values.shape[1:])
    return [(out[0][h], out[1][h], out[2][h], attributes[h]) for h in range(2)]


def _empty_like(rig, name) -> Rig:
    attributes = {k: np.empty((0,) + np.asarray(v).shape[1:], np.asarray(v).dtype)
                  for k, v in rig.attributes.items()}
    return Rig(vertices=np.empty((0, 3)), faces=np.empty((0, 3), np.int64),
               joints=np.empty((0, 4), np.int64), weights=np.empty((0, 4)), skeleton=rig.skeleton,
               clips=list(rig.clips), attributes=attributes, name=name)


def _copy(rig, name) -> Rig:
    return Rig(vertices=np.array(rig.vertices, dtype=np.float64), faces=np.array(rig.faces),
               joints=np.array(rig.joints), weights=np.array(rig.weights), skeleton=rig.skeleton,
               clips=list(rig.clips), attributes={k: np.array(v) for k, v in rig.attributes.items()},
               name=name)


def cut_details(rig: Rig, normal, point, pose=None, cap: bool = False) -> CutResult:
    """``cut`` with the bookkeeping (``CutResult``): which input vertex each output vertex comes from,
    the new vertices' edges and parameters, the plane and tolerances. Same arguments as ``cut``."""
    vertices, joints, weights = _mesh(rig)
    plane = _plane(normal, point)
    if not isinstance(cap, (bool, np.bool_)):
        raise InvalidInputError(f"cap must be True or False, got {cap!r}")
    affines = None
    if pose is None:
        positions = vertices
    else:
        affines = check_pose(rig, pose).bone_affines()
        positions = skin_affine(vertices, joints, weights, affines)
    topo = rig_topology(rig)

    sign, tol, diag = _classify(plane, positions, topo.representative, ON_PLANE_TOLERANCE)
    (pos_faces, neg_faces, pos_src, neg_src,
     new_lo, new_hi, new_t, new_point) = _split(plane, positions, np.ascontiguousarray(rig.faces, np.int64),
                                                topo.faces, topo.welded, topo.representative, sign,
                                                topo.face_vertex_edges, topo.vertex_edges)
    names = (f"{rig.name}_positive", f"{rig.name}_negative")
    if len(pos_faces) == 0 or len(neg_faces) == 0:
        on_positive = len(pos_faces) > 0
        warnings.warn(f"the cutting plane does not cross the mesh of {rig.name!r}: it lies entirely on "
                      f"the {'positive' if on_positive else 'negative'} side; the other half is empty",
                      PlaneMissesMeshWarning, stacklevel=3)
        whole, empty = _copy(rig, names[1 - on_positive]), _empty_like(rig, names[on_positive])
        everything = np.arange(len(vertices), dtype=np.int64)
        halves = (whole, empty) if on_positive else (empty, whole)
        sources = (everything, np.empty(0, np.int64)) if on_positive else (np.empty(0, np.int64), everything)
        return CutResult(halves[0], halves[1], sources, np.empty((0, 2), np.int64), np.empty(0),
                         np.empty((0, 3)), (len(halves[0].vertices), len(halves[1].vertices)), plane, tol,
                         0.0)

    new_joints, new_weights = blend_weight_rows(np.stack([new_lo, new_hi], axis=1),
                                                np.stack([1.0 - new_t, new_t], axis=1), joints, weights)
    residual = 0.0
    if affines is None:
        new_rest = new_point
    else:
        guess = vertices[new_lo] * (1.0 - new_t)[:, None] + vertices[new_hi] * new_t[:, None]
        new_rest, residuals, singular = _place_in_rest(new_point, guess, new_joints, new_weights, affines)
        residual = float(residuals.max()) if len(residuals) else 0.0
        if singular.any() or residual > PLACEMENT_TOLERANCE * diag:
            warnings.warn(f"{int(singular.sum())} new vertices have a singular blended transform in this "
                          f"pose and {int((residuals > PLACEMENT_TOLERANCE * diag).sum())} miss the plane "
                          f"by more than {PLACEMENT_TOLERANCE:g} of the diagonal (largest {residual:.3g}); "
                          f"they keep their interpolated rest positions", RuntimeWarning, stacklevel=3)
    arrays = _split_arrays(rig, vertices, joints, weights, pos_src, neg_src, new_lo, new_hi, new_t,
                           new_rest, new_joints, new_weights)
    halves = [Rig(vertices=v, faces=f, joints=j, weights=w, skeleton=rig.skeleton, clips=list(rig.clips),
                  attributes=a, name=names[h])
              for h, ((v, j, w, a), f) in enumerate(zip(arrays, (pos_faces, neg_faces)))]
    new_src = np.full(len(new_lo), NEW_VERTEX, np.int64)
    sources = [np.concatenate([pos_src, new_src]), np.concatenate([neg_src, new_src])]
    if cap:
        cut_positions = [np.concatenate([positions[pos_src], new_point]),
                         np.concatenate([positions[neg_src], new_point])]
        for h in range(2):
            halves[h], sources[h] = _cap(halves[h], sources[h], cut_positions[h], plane, tol, topo,
                                         outward=-1.0 if h == 0 else 1.0, affines=affines)
    return CutResult(halves[0], halves[1], tuple(sources), np.stack([new_lo, new_hi], axis=1), new_t,
                     new_point, (len(pos_src), len(neg_src)), plane, tol, residual)


def cut(rig: Rig, normal, point, pose=None, cap: bool = False):
    """Cut ``rig`` with the plane through ``point`` with normal ``normal``.

    Parameters
    ----------
    rig : Rig
    normal : (3,) float, any non-zero length; it picks which half comes first
    point : (3,) float, a point of the plane
    pose : Pose or None
        Cut the mesh as posed (skinned) in this pose; the new vertices are placed in rest space so that
        skinning the halves in ``pose`` puts them exactly on the plane. None cuts the stored
        bind-pose vertices ``rig.vertices``. What a viewer shows at rest is ``skin(rig)``; where that
        differs from the stored mesh (bind matrices that are not the rest pose's, e.g. a mesh node
        with an offset), pass ``pose=rig.rest_pose()`` to cut what it shows.
    cap : bool
        Close each half with planar caps over the loops the cut opened.

    Returns
    -------
    (positive, negative) : (Rig, Rig)
        positive: the part on the side the normal points to (signed distance > 0), negative: the other
        one; vertices on the plane are in both. Full skeleton and clips in both. When the plane misses
        the mesh: the whole rig (a copy) on the side it lies on and an empty rig on the other, with a
        ``PlaneMissesMeshWarning``.

    Raises
    ------
    InvalidInputError
        Zero or non-finite normal or point, wrong shapes, a rig without faces or with inconsistent
        arrays, a pose of another skeleton.
    """
    result = cut_details(rig, normal, point, pose=pose, cap=cap)
    return result.positive, result.negative


# ---- caps ---------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _orient(ax, ay, bx, by, cx, cy):
    """Twice the signed area of triangle abc (> 0: counter-clockwise)."""
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _is_ear(xy, ids, nxt, p, i, q):
    """Whether corner i (between p and q) of the remaining polygon can be clipped: strictly convex, and
    no other remaining vertex inside or on the triangle (vertices that repeat one of its three, as
    bridge endpoints do, are ignored)."""
    ax, ay = xy[p, 0], xy[p, 1]
    bx, by = xy[i, 0], xy[i, 1]
    cx, cy = xy[q, 0], xy[q, 1]
    if _orient(ax, ay, bx, by, cx, cy) <= 0.0:
        return False
    v = nxt[q]
    while v != p:
        if ids[v] != ids[p] and ids[v] != ids[i] and ids[v] != ids[q]:
            px, py = xy[v, 0], xy[v, 1]
            if (_orient(ax, ay, bx, by, px, py) >= 0.0 and _orient(bx, by, cx, cy, px, py) >= 0.0
                    and _orient(cx, cy, ax, ay, px, py) >= 0.0):
                return False
        v = nxt[v]
    return True


@njit(cache=True, nogil=True, error_model="numpy")
def _ear_clip(xy, ids):
    """Triangulate a counter-clockwise simple polygon (possibly weakly simple: holes bridged in, with
    repeated vertices) by ear clipping.

    xy : (k, 2) float64 vertices in order ; ids : (k,) int64 vertex identities (repeats share one)
    returns (k - 2, 3) int64 counter-clockwise triangles of polygon positions
    """
    k = xy.shape[0]
    tris = np.empty((max(k - 2, 0), 3), np.int64)
    if k < 3:
        return tris
    prev = np.empty(k, np.int64)
    nxt = np.empty(k, np.int64)
    for j in range(k):
        prev[j] = (j - 1) % k
        nxt[j] = (j + 1) % k
    remaining = k
    count = 0
    i = np.int64(0)
    misses = 0
    while remaining > 3:
        p = prev[i]
        q = nxt[i]
        if _is_ear(xy, ids, nxt, p, i, q):
            pass
        elif misses > remaining:
            # A full turn without an ear: the polygon is degenerate here (collinear or touching
            # vertices from float rounding). Clip the most convex corner to make progress.
            best, best_area, j = i, -np.inf, i
            for _ in range(remaining):
                a = _orient(xy[prev[j], 0], xy[prev[j], 1], xy[j, 0], xy[j, 1], xy[nxt[j], 0], xy[nxt[j], 1])
                if a > best_area:
                    best, best_area = j, a
                j = nxt[j]
            i, p, q = best, prev[best], nxt[best]
        else:
            i = q
            misses += 1
            continue
        tris[count, 0] = p
        tris[count, 1] = i
        tris[count, 2] = q
        count += 1
        nxt[p] = q
        prev[q] = p
        remaining -= 1
        misses = 0
        i = q
    tris[count, 0] = prev[i]
    tris[count, 1] = i
    tris[count, 2] = nxt[i]
    return tris


def _signed_area(xy) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(x @ np.roll(y, -1) - y @ np.roll(x, -1))


def _inside(point, xy) -> bool:
    """Even-odd rule: whether ``point`` (2,) is inside the closed polygon ``xy`` (k, 2)."""
    a, b = xy, np.roll(xy, -1, axis=0)
    crosses = (a[:, 1] > point[1]) != (b[:, 1] > point[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (point[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(crosses & (x > point[0])) % 2)


def _bridge(polygon: list, hole: list, xy) -> list:
    """Splice ``hole`` (clockwise) into ``polygon`` (counter-clockwise), both lists of ids indexing
    ``xy``, through a bridge from the hole's rightmost vertex M to a polygon vertex visible from it
    (Eberly, "Triangulation by ear clipping", section 3)."""
    h = int(np.argmax(xy[hole, 0]))
    mx, my = xy[hole[h]]
    ring = np.asarray(polygon)
    a, b = xy[ring], xy[np.roll(ring, -1)]
    crosses = (a[:, 1] > my) != (b[:, 1] > my)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (my - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    hits = np.flatnonzero(crosses & (x >= mx))
    if len(hits) == 0:
        return None
    e = int(hits[np.argmin(x[hits])])
    ix = float(x[e])
    j = e if a[e, 0] >= b[e, 0] else (e + 1) % len(ring)     # the hit edge's end further along +x
    px, py = xy[ring[j]]
    # polygon vertices inside the triangle M, I, P would hide P: take the one closest in angle to +x
    q = xy[ring]
    s1 = _orient_np(mx, my, ix, my, q[:, 0], q[:, 1])
    s2 = _orient_np(ix, my, px, py, q[:, 0], q[:, 1])
    s3 = _orient_np(px, py, mx, my, q[:, 0], q[:, 1])
    sense = np.sign(_orient_np(mx, my, ix, my, px, py)) or 1.0
    inside = (sense * s1 > 0) & (sense * s2 > 0) & (sense * s3 > 0) & (q[:, 0] > mx)
    if inside.any():
        cand = np.flatnonzero(inside)
        dx, dy = q[cand, 0] - mx, np.abs(q[cand, 1] - my)
        j = int(cand[np.lexsort((dx, dy / dx))[0]])
    return polygon[:j + 1] + hole[h:] + hole[:h + 1] + polygon[j:]


def _orient_np(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


def _cap_triangles(loops: list, xy) -> np.ndarray:
    """Triangles (t, 3) over the loops' vertex ids, covering the region the loops bound.

    loops : list of lists of ids into ``xy`` (w, 2), oriented as the cap must run along them: outer
        loops counter-clockwise, holes clockwise (what a consistently oriented closed mesh gives)
    returns (t, 3) int64, counter-clockwise where the loops are.

    Nesting comes from the orientation, not from even-odd counting: each hole is bridged into the
    smallest outer loop around it (so a hollow ball's cap is an annulus, and an island inside a hole
    is an outer loop of its own), while outer loops that overlap (sections of a self-intersecting mesh,
    such as interpenetrating fingers) get overlapping caps of their own instead of cancelling. A hole
    with no outer loop around it (possible only on an open or inconsistently oriented mesh) is capped
    on its own, keeping its orientation.
    """
    polys = [np.asarray(loop, np.int64) for loop in loops if len(loop) >= 3]
    areas = [_signed_area(xy[p]) for p in polys]
    outers = {i: [] for i in range(len(polys)) if areas[i] > 0}
    lone_holes = []
    for i in range(len(polys)):
        if areas[i] > 0:
            continue
        # a probe point: the midpoint of the hole's longest edge (its vertices may touch the outer loop)
        a, b = xy[polys[i]], xy[np.roll(polys[i], -1)]
        e = int(np.argmax(np.sum((b - a) ** 2, axis=1)))
        probe = 0.5 * (a[e] + b[e])
        around = [o for o in outers if _inside(probe, xy[polys[o]])]
        if around:
            outers[min(around, key=lambda o: areas[o])].append(i)
        else:
            lone_holes.append(i)
    triangles = [np.empty((0, 3), np.int64)]
    for o, holes in outers.items():
        polygon = list(polys[o])
        for hole in sorted(holes, key=lambda i: -xy[polys[i], 0].max()):
            merged = _bridge(polygon, list(polys[hole]), xy)
            if merged is None:
                lone_holes.append(hole)
            else:
                polygon = merged
        ids = np.asarray(polygon, np.int64)
        triangles.append(ids[_ear_clip(np.ascontiguousarray(xy[ids]), ids)])
    for hole in lone_holes:
        ids = polys[hole][::-1]
        triangles.append(ids[_ear_clip(np.ascontiguousarray(xy[ids]), ids)][:, ::-1])
    return np.concatenate(triangles)


def _plane_basis(normal):
    """Unit u, v with u × v = normal (unit)."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def _cap(half: Rig, sources, cut_positions, plane, tol, original: Topology, outward: float, affines):
    """Close ``half`` over the loops the cut opened; returns the capped rig and its sources.

    cut_positions : (n, 3) the half's vertices in the space that was cut (posed for a posed cut)
    outward : -1 for the positive half (its caps face -n), +1 for the negative half
    """
    # The cut's loops run along edges whose two ends are on the plane, and every face on such an edge
    # has both ends as corners: the welded topology of the faces with two or more corners on the plane
    # has the same boundary edges there as the whole half's, and is much smaller.
    n = len(half.vertices)
    dist = np.empty((n, 1))
    point_plane_distance_batch(np.broadcast_to(plane, (n, 4)), cut_positions, dist)
    on_vertex = np.abs(dist[:, 0]) <= tol
    near = half.faces[np.count_nonzero(on_vertex[half.faces], axis=1) >= 2]
    if len(near) == 0:
        return half, sources
    used, sub_faces = np.unique(near, return_inverse=True)
    ht = topology(half.vertices[used], sub_faces.reshape(-1, 3))
    rep = used[ht.representative]                 # the half's vertex for each welded sub-vertex
    on = on_vertex[rep]
    be = ht.boundary_edges
    inc = ht.edge_face_offsets[be]
    f, k = ht.edge_face_faces[inc], ht.edge_face_corners[inc].astype(np.int64)
    start, end = ht.faces[f, k], ht.faces[f, (k + 1) % 3]
    keep = on[start] & on[end]
    # an edge between two input vertices that was already a boundary edge of the input is not a cut
    src_a, src_b = sources[rep[start]], sources[rep[end]]
    both = np.flatnonzero(keep & (src_a >= 0) & (src_b >= 0))
    if len(both):
        e = original.find_edges(original.welded[src_a[both]], original.welded[src_b[both]])
        was_boundary = (e >= 0) & (original.edge_face_counts[np.maximum(e, 0)] == 1)
        keep[both[was_boundary]] = False
    start, end = start[keep], end[keep]
    if len(start) == 0:
        return half, sources
    normal = outward * plane[:3]
    u, v = _plane_basis(normal)
    loop_welded = np.unique(np.concatenate([start, end]))
    local = np.full(ht.n_welded, -1, np.int64)
    local[loop_welded] = np.arange(len(loop_welded))
    p = cut_positions[rep[loop_welded]]
    xy = np.stack([p @ u, p @ v], axis=1)
    # A cap runs along each loop against its faces' direction, so it continues their orientation:
    # chain the reversed edges. Where loops touch at a vertex (the plane through a saddle vertex),
    # the sharpest left turn keeps each loop around its own region (the region lies to the left).
    rs, re = local[end], local[start]

    def sharpest_left(previous, vertex, candidates):
        back = xy[previous] - xy[vertex]
        out = xy[re[candidates]] - xy[vertex]
        clockwise = np.mod(np.arctan2(back[1], back[0]) - np.arctan2(out[:, 1], out[:, 0]), 2 * np.pi)
        return int(np.argmin(np.where(clockwise > 0, clockwise, 2 * np.pi)))

    loops = directed_loops(rs, re, choose=sharpest_left)
    triangles = _cap_triangles(loops, xy)
    if len(triangles) == 0:
        return half, sources

    # cap vertices: one per loop vertex that a cap triangle uses (chains that did not close have none)
    kept, triangles = np.unique(triangles, return_inverse=True)
    triangles = triangles.reshape(-1, 3)
    xy = xy[kept]
    row = rep[loop_welded[kept]]                 # the half's vertex each cap vertex copies
    attributes = {}
    for key, values in half.attributes.items():
        values = np.asarray(values)
        extra = values[row].astype(np.float64)
        if key == "NORMAL" and values.shape[1:] == (3,):
            extra = _cap_normals(half, row, normal, affines)
        elif key.startswith("TEXCOORD") and values.shape[1:] == (2,):
            extent = max(float(np.ptp(xy[:, 0])), float(np.ptp(xy[:, 1])), 1e-300)
            extra = (xy - xy.min(axis=0)) / extent        # planar projection, aspect kept
        attributes[key] = np.concatenate([values, extra.astype(values.dtype, copy=False)])
    capped = Rig(vertices=np.concatenate([half.vertices, half.vertices[row]]),
                 faces=np.concatenate([half.faces, triangles + n]),
                 joints=np.concatenate([half.joints, half.joints[row]]),
                 weights=np.concatenate([half.weights, half.weights[row]]),
                 skeleton=half.skeleton, clips=half.clips, attributes=attributes, name=half.name)
    return capped, np.concatenate([sources, np.full(len(row), CAP_VERTEX, np.int64)])


def _cap_normals(half, rows, normal, affines):
    """Rest-space normals of cap vertices that skin to ``normal``: normals map by the cofactor of the
    blended linear part L, so the rest normal is L^T n (normalised); in a rest cut, n itself."""
    if affines is None:
        return np.tile(normal, (len(rows), 1))
    blend = np.einsum("vk,vkc->vc", half.weights[rows], affines[half.joints[rows]]).reshape(-1, 3, 4)
    out = np.einsum("vji,j->vi", blend[:, :, :3], normal)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.divide(out, length, out=np.tile(normal, (len(rows), 1)), where=length > 0)
