"""Blending skin weight rows: the weights of vertices created on edges (cut, tear) and inside faces
(tear), kept in the layout every rig has: 4 influences, largest first, summing to 1."""
import math

import numpy as np

from ..algebra.vec3 import _copy_row
from ..generated.kernels import affine_point
from .._shared.jit import helper, kernel, F2, I1, I2, b1, i8


@kernel((I2, F2, I2, F2), cost=0.6)
def blend_weight_rows(src, coef, joints, weights):
    """Weights of interpolated vertices: Σ_r coef[i, r] · (row src[i, r]) over the union of the rows'
    bones, the 4 largest kept and renormalised, sorted by decreasing weight; unused slots bone 0 with
    weight 0 (the layout ``validate.check_mesh`` produces). Edge points blend 2 rows (1 − t, t),
    points inside faces 3 (barycentric).

    src : (k, r) int64 ; coef : (k, r) float64 ; joints, weights : (n, 4)
    returns joints (k, 4) int64, weights (k, 4) float64
    """
    k = src.shape[0]
    out_j = np.zeros((k, 4), np.int64)
    out_w = np.zeros((k, 4))
    bones = np.empty(4 * src.shape[1], np.int64)
    values = np.empty(4 * src.shape[1])
    for i in range(k):
        count = 0
        for r in range(src.shape[1]):
            v = src[i, r]
            for s in range(4):
                w = coef[i, r] * weights[v, s]
                if w <= 0.0:
                    continue
                found = False
                for q in range(count):
                    if bones[q] == joints[v, s]:
                        values[q] += w
                        found = True
                        break
                if not found:
                    bones[count] = joints[v, s]
                    values[count] = w
                    count += 1
        kept = min(4, count)
        total = 0.0
        for slot in range(kept):            # selection of the largest (ties: the bone met first)
            best = slot
            for q in range(slot + 1, count):
                if values[q] > values[best]:
                    best = q
            bones[slot], bones[best] = bones[best], bones[slot]
            values[slot], values[best] = values[best], values[slot]
            total += values[slot]
        for slot in range(kept):
            out_j[i, slot] = bones[slot]
            out_w[i, slot] = values[slot] / total
    return out_j, out_w


@helper
def _blended(joints, weights, affines, i):
    """(12,) the blended row-major 3x4 map Σ_k w_k A[joints[i, k]] of vertex i."""
    out = np.zeros(12)
    for s in range(4):
        w = weights[i, s]
        if w != 0.0:
            a = affines[joints[i, s]]
            for c in range(12):
                out[c] += w * a[c]
    return out


@helper
def _solve_linear(m, r):
    """x with L x = r for the linear part L of a row-major 3x4 map ``m`` (Cramer's rule); NaN if L
    is singular."""
    a, b, c = m[0], m[1], m[2]
    d, e, f = m[4], m[5], m[6]
    g, h, i = m[8], m[9], m[10]
    c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * c0 + b * c1 + c * c2
    out = np.empty(3)
    if det == 0.0:
        out[:] = np.nan
        return out
    out[0] = (r[0] * c0 + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) / det
    out[1] = (r[0] * c1 + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) / det
    out[2] = (r[0] * c2 + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) / det
    return out


@helper
def _to_rest(target, guess, blend):
    """The rest position x whose blended map ``blend`` (12,) puts it at ``target`` (3,): solved
    relative to ``guess`` (the interpolated rest position, close to the answer) and refined once on
    the residual (generated ``affine_point``), so the error is that of one map evaluation.
    returns x (3,), residual |blend(x) - target| (inf when the map is singular: x stays the guess)"""
    x = guess.copy()
    r = np.empty(3)
    for _ in range(2):
        y = affine_point(blend, x)
        r[0], r[1], r[2] = target[0] - y[0], target[1] - y[1], target[2] - y[2]
        dx = _solve_linear(blend, r)
        if not (math.isfinite(dx[0]) and math.isfinite(dx[1]) and math.isfinite(dx[2])):
            return x, np.inf
        x += dx
    y = affine_point(blend, x)
    return x, math.sqrt((target[0] - y[0]) ** 2 + (target[1] - y[1]) ** 2 + (target[2] - y[2]) ** 2)


@kernel((F2, i8, I2, F2, I1, b1), cost=0.3)
def _rows(out, n, src, coef, twin_src, unit):
    """An attribute extended to the torn mesh, in place: ``out`` (n + v + t, c) float64 holds the
    original rows in its first n; the new vertices' rows interpolate their sources (Σ_r coef[i, r] ·
    out[src[i, r]], renormalised to unit length when ``unit``: normals), the twins' rows copy their
    vertex's."""
    c = out.shape[1]
    v, t = src.shape[0], twin_src.shape[0]
    for i in range(v):
        for q in range(c):
            out[n + i, q] = (coef[i, 0] * out[src[i, 0], q] + coef[i, 1] * out[src[i, 1], q]
                             + coef[i, 2] * out[src[i, 2], q])
        if unit:
            length = 0.0
            for q in range(c):
                length += out[n + i, q] ** 2
            if length > 0.0:
                length = math.sqrt(length)
                for q in range(c):
                    out[n + i, q] /= length
    for i in range(t):
        _copy_row(out, n + v + i, out, twin_src[i])


@helper
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


@kernel((F2, F2, I2, F2, F2), cost=1.2)
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
