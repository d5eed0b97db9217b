"""New vertices on edges and inside faces: their weights, attributes and rest positions.

Cut, tear (and every later operation that adds vertices) describe a new vertex the same way: the
existing vertices it lies between and its coefficients there (``NewVertices``): (1 - t, t) for the
point at parameter t of an edge, the barycentric coordinates for a point inside a face. From that
one description come

* its skin weights (``blend_weight_rows``): the sources' rows blended, the 4 largest kept and
  renormalised, in the layout every rig has (4 influences, largest first, summing to 1);
* its attributes (``interpolate_attribute``): interpolated, normals renormalised, application-specific
  ("_"-prefixed) data copied from the dominant source, since it may not be interpolable (labels);
* its rest position when it was made on a posed mesh (``place_in_rest``): the point x whose own
  blended 3x4 map puts it on its posed target, solved relative to the interpolated rest position.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._shared.jit import F2, I1, I2, helper, i8, inlined, kernel
from ..generated.kernels import affine_point

__all__ = ["NewVertices", "on_edges", "blend_weight_rows", "attribute_rule", "interpolate_attribute",
           "interpolate_in_place", "place_in_rest"]


class NewVertices(NamedTuple):
    """Where new vertices lie among existing ones.

    src : (k, r) int64 the existing vertices each new vertex lies between (r = 2 on an edge, 3 in a
        face)
    coef : (k, r) float64 its coefficients there, summing to 1
    """

    src: np.ndarray
    coef: np.ndarray


def on_edges(lo, hi, t) -> NewVertices:
    """New vertices at parameter ``t`` (k,) of the edges ``lo`` -> ``hi`` (k,): (1 - t) x_lo + t x_hi."""
    src = np.empty((len(t), 2), np.int64)           # filled by columns: np.stack costs 3x as much
    src[:, 0], src[:, 1] = lo, hi
    coef = np.empty((len(t), 2))
    coef[:, 1] = t
    np.subtract(1.0, coef[:, 1], out=coef[:, 0])
    return NewVertices(src, coef)


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
                if w > 0.0:
                    count = accumulate(bones, values, count, joints[v, s], w)
        kept = min(4, count)
        total = largest_first(bones, values, count, kept)
        for slot in range(kept):
            out_j[i, slot] = bones[slot]
            out_w[i, slot] = values[slot] / total
    return out_j, out_w


@inlined
def accumulate(keys, values, count, key, value):
    """Add ``value`` to the entry of ``key`` among the first ``count`` of keys, values (a new entry at
    the end when there is none); returns the number of entries."""
    for q in range(count):
        if keys[q] == key:
            values[q] += value
            return count
    keys[count], values[count] = key, value
    return count + 1


@inlined
def largest_first(keys, values, count, kept):
    """Move the ``kept`` largest of the first ``count`` values, with their keys, to the front, largest
    first (ties: the entry met first); returns their sum."""
    total = 0.0
    for slot in range(kept):                # selection of the largest
        best = slot
        for q in range(slot + 1, count):
            if values[q] > values[best]:
                best = q
        keys[slot], keys[best] = keys[best], keys[slot]
        values[slot], values[best] = values[best], values[slot]
        total += values[slot]
    return total


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


#: how an attribute's rows are made for new vertices (``attribute_rule``)
LINEAR, UNIT, DOMINANT = np.int64(0), np.int64(1), np.int64(2)


def attribute_rule(name: str, width: int):
    """LINEAR for most attributes; UNIT (interpolated, renormalised) for "NORMAL" (n, 3); DOMINANT
    (the row of the source with the largest coefficient, the first on a tie) for application-specific
    attributes ("_" prefix, e.g. the tear's labels), which may not be interpolable."""
    if name.startswith("_"):
        return DOMINANT
    return UNIT if name == "NORMAL" and width == 3 else LINEAR


@helper
def _combine(values, src, coef, i, rule, out, row):
    """out[row] = the row of new vertex i made from ``values`` by ``rule``."""
    c = values.shape[1]
    if rule == DOMINANT:
        best = 0
        for r in range(1, src.shape[1]):
            if coef[i, r] > coef[i, best]:
                best = r
        for q in range(c):
            out[row, q] = values[src[i, best], q]
        return
    length = 0.0
    for q in range(c):
        x = 0.0
        for r in range(src.shape[1]):
            x += coef[i, r] * values[src[i, r], q]
        out[row, q] = x
        length += x * x
    if rule == UNIT and length > 0.0:          # a zero normal stays zero
        inverse = 1.0 / math.sqrt(length)
        for q in range(c):
            out[row, q] *= inverse


@kernel((F2, I2, F2, i8), cost=0.3)
def _interpolate(values, src, coef, rule):
    """(k, c) rows of the new vertices ``src``, ``coef`` (k, r) made from ``values`` (n, c) by ``rule``."""
    out = np.empty((src.shape[0], values.shape[1]))
    for i in range(src.shape[0]):
        _combine(values, src, coef, i, rule, out, i)
    return out


@kernel((F2, i8, I2, F2, i8, I1), cost=0.3)
def interpolate_in_place(rows, first, src, coef, rule, copies):
    """Fill the rows of an array extended for new vertices, in place (no copy of the sources):
    ``rows[first:first + k]`` (float64 (N, c)) with the new vertices' rows, made by ``rule`` from rows
    below ``first``, then the t rows after them with copies of the rows ``copies`` (t,) (the tear's
    twins)."""
    k = src.shape[0]
    for i in range(k):
        _combine(rows, src, coef, i, rule, rows, first + i)
    for i in range(copies.shape[0]):
        for q in range(rows.shape[1]):
            rows[first + k + i, q] = rows[copies[i], q]


def interpolate_attribute(name: str, values, new: NewVertices) -> np.ndarray:
    """The rows of attribute ``name`` for new vertices (``attribute_rule``).

    values : (n, ...) the attribute's rows for the existing vertices
    returns (k, ...) of ``values``' dtype
    """
    values = np.asarray(values)
    flat = np.ascontiguousarray(values.reshape(len(values), -1), dtype=np.float64)
    rows = _interpolate(flat, new.src, new.coef, attribute_rule(name, flat.shape[1]))
    return rows.reshape((len(rows),) + values.shape[1:]).astype(values.dtype, copy=False)


@kernel((F2, F2, I2, F2, F2), cost=1.2)
def place_in_rest(targets, guesses, joints, weights, affines):
    """Rest positions x with Σ_k w_k A_k(x) = target for each new vertex (its own blended 3x4 map).

    targets : (k, 3) posed positions ; guesses : (k, 3) interpolated rest positions
    joints, weights : (k, 4) the new vertices' own ; affines : (B, 12) the pose's bone maps
    returns rest (k, 3), residual (k,) |B x - target| (inf where B is singular: x stays the guess)
    """
    k = targets.shape[0]
    rest = np.empty((k, 3))
    residual = np.empty(k)
    for i in range(k):
        x, res = _to_rest(targets[i], guesses[i], _blended(joints, weights, affines, i))
        rest[i, 0], rest[i, 1], rest[i, 2] = x[0], x[1], x[2]
        residual[i] = res
    return rest, residual
