"""The drill's bit: the solid within ``radius`` of the segment start -> end (a cylinder around the bit's
travel with a round tip at ``end``, and a round back at ``start``), and the distances the drill measures
with it.

The distance of a point from the segment is the distance from its axis line (generated
``point_line_distance``: the outer product (x - a) ^ u, relative to a point of the axis) where the point
projects inside the travel, else from the nearer end. ``f(x) = distance - radius`` is negative inside
the bit and convex, so along a mesh edge whose ends lie on either side it has exactly one root, found
to the last bit of the edge parameter (``crossing``): a rim vertex lies on the bit's surface to rounding.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..._shared.checks import float_array, real_number
from ..._shared.jit import helper, inlined
from ...errors import InvalidInputError
from ...generated.kernels import barycentric, point_line_distance

__all__ = ["Bit", "bit"]


class Bit(NamedTuple):
    """A drill bit: start (3,), end (3,) float64 (its travel), radius > 0."""

    start: np.ndarray
    end: np.ndarray
    radius: float


def bit(start, end, radius) -> Bit:
    """A checked ``Bit``: finite points, a travel of non-zero length, a positive finite radius."""
    a = float_array(start, "start", 3, ndim=1).copy()
    b = float_array(end, "end", 3, ndim=1).copy()
    r = real_number(radius, "radius")
    if not r > 0.0:
        raise InvalidInputError(f"radius must be positive, got {r}")
    if np.array_equal(a, b):
        raise InvalidInputError("start and end are the same point: the bit has no travel (give the hole's "
                                "direction by an end point beyond the start)")
    return Bit(a, b, r)


@helper
def segment_distance(start, end, axis, x):
    """Distance of x (3,) from the segment start -> end, ``axis`` = end - start (3,) (made once by a
    caller that measures many points)."""
    dx, dy, dz = axis[0], axis[1], axis[2]
    wx, wy, wz = x[0] - start[0], x[1] - start[1], x[2] - start[2]
    along = wx * dx + wy * dy + wz * dz
    if along <= 0.0:
        return math.sqrt(wx * wx + wy * wy + wz * wz)
    if along >= dx * dx + dy * dy + dz * dz:
        ex, ey, ez = x[0] - end[0], x[1] - end[1], x[2] - end[2]
        return math.sqrt(ex * ex + ey * ey + ez * ez)
    return point_line_distance(start, axis, x)


@helper
def put_on_edge(p, q, t, out):
    """out (3,) := p + t (q - p); out."""
    for k in range(3):
        out[k] = p[k] + t * (q[k] - p[k])
    return out


@helper
def _closest_on_edge(start, end, p, q):
    """The least distance between the segment p -> q and the bit's segment (Ericson, "Real-Time
    Collision Detection", 5.1.9: the closest points' parameters, clamped; in coordinates relative to
    the bit's start)."""
    d1x, d1y, d1z = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    d2x, d2y, d2z = end[0] - start[0], end[1] - start[1], end[2] - start[2]
    rx, ry, rz = p[0] - start[0], p[1] - start[1], p[2] - start[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    c = d1x * rx + d1y * ry + d1z * rz
    b = d1x * d2x + d1y * d2y + d1z * d2z
    s = 0.0
    if a > 0.0:
        denom = a * e - b * b
        if denom > 0.0:
            s = min(max((b * f - c * e) / denom, 0.0), 1.0)
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0) if a > 0.0 else 0.0
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0) if a > 0.0 else 0.0
    dx = rx + s * d1x - t * d2x
    dy = ry + s * d1y - t * d2y
    dz = rz + s * d1z - t * d2z
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@helper
def _closest_on_face(start, end, a, b, c, x):
    """The least distance of triangle abc from the bit's segment: over its edges, the segment's ends
    projected inside it, and 0 where the segment pierces it (``x`` (3,): scratch)."""
    best = min(_closest_on_edge(start, end, a, b), min(_closest_on_edge(start, end, b, c),
                                                       _closest_on_edge(start, end, c, a)))
    for e in (start, end):
        la, lb, lc = barycentric(a, b, c, e)
        if la >= 0.0 and lb >= 0.0 and lc >= 0.0:
            fx, fy, fz = (la * a[0] + lb * b[0] + lc * c[0] - e[0], la * a[1] + lb * b[1] + lc * c[1] - e[1],
                          la * a[2] + lb * b[2] + lc * c[2] - e[2])
            best = min(best, math.sqrt(fx * fx + fy * fy + fz * fz))
    # the segment's crossing of the triangle's plane, if it lies inside the triangle
    ux, uy, uz, vx, vy, vz = b[0] - a[0], b[1] - a[1], b[2] - a[2], c[0] - a[0], c[1] - a[1], c[2] - a[2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    da = (start[0] - a[0]) * nx + (start[1] - a[1]) * ny + (start[2] - a[2]) * nz
    db = (end[0] - a[0]) * nx + (end[1] - a[1]) * ny + (end[2] - a[2]) * nz
    if (da < 0.0) != (db < 0.0) and da != db:
        la, lb, lc = barycentric(a, b, c, put_on_edge(start, end, da / (da - db), x))
        if la >= 0.0 and lb >= 0.0 and lc >= 0.0:
            best = 0.0
    return best


#: every point of a triangle lies within its longest edge / sqrt(3) of a corner (its circumradius when
#: acute, whose largest angle is at least 60 degrees; half the longest edge when not)
NEAREST_CORNER = 1.0 / math.sqrt(3.0)


@helper
def surface_crosses(positions, p, q, r, signed, longest, start, end, radius, x):
    """Whether the bit's surface passes through triangle p, q, r (rows of ``positions`` (P, 3), ``signed``
    (P,) their ``signed_distances``, ``longest`` its longest edge's length): f above 0 at a corner and
    below 0 somewhere on it (at a corner, or the least over the face, ``_closest_on_face``), f being
    convex. The least is computed only where a bound leaves it open: f is 1-Lipschitz and every point of
    the face lies within ``NEAREST_CORNER`` times its longest edge of a corner. ``x`` (3,): scratch."""
    fp, fq, fr = signed[p], signed[q], signed[r]
    if max(fp, max(fq, fr)) <= 0.0 or min(fp, min(fq, fr)) - NEAREST_CORNER * longest > 0.0:
        return False
    if min(fp, min(fq, fr)) < 0.0:
        return True
    return _closest_on_face(start, end, positions[p], positions[q], positions[r], x) - radius < 0.0


@helper
def signed_distances(positions, first, start, end, radius):
    """f = distance - radius of each row of ``positions`` (P, 3) from ``first`` on (P - first,): negative
    inside the bit."""
    out, axis = np.empty(positions.shape[0] - first), end - start
    for i in range(first, positions.shape[0]):
        out[i - first] = segment_distance(start, end, axis, positions[i]) - radius
    return out


#: every how many steps of ``crossing``'s root search one is a bisection (so that the bracket at least
#: halves that often whatever the secant steps do)
BISECT_EVERY = 4


#: the half-widths, in the edge parameter, of the brackets ``crossing`` tries about its closed-form guess
#: (off by rounding only: the first brackets the crossing where the edge is not nearly tangent), smallest
#: first
GUESS_BRACKETS = (3e-14, 1e-11, 1e-8)


@helper
def crossing(p, q, f_p, f_q, start, end, axis, radius, x):
    """The parameter t where the edge p -> q (3,), one end inside the bit and the other outside (f there
    ``f_p``, ``f_q``: their ``signed_distances``), meets the bit's surface (``axis`` = end - start; ``x``
    (3,) scratch): a bracket narrowed by regula falsi steps (Illinois: an end kept twice has its value
    halved, so both ends close in) and a bisection every ``BISECT_EVERY`` steps, until it cannot shrink;
    the end of the bracket nearer the surface. The bracket is the first of ``GUESS_BRACKETS`` about the
    closed-form crossing (``_guess``) across which f changes sign as across the edge, else [0, 1]."""
    lo, hi = 0.0, 1.0
    f_lo, f_hi = f_p, f_q
    guess = _guess(p, q, start, end, axis, radius)
    for half in GUESS_BRACKETS:
        a, b = guess - half, guess + half
        if not 0.0 < a < b < 1.0:
            break
        f_a = segment_distance(start, end, axis, put_on_edge(p, q, a, x)) - radius
        f_b = segment_distance(start, end, axis, put_on_edge(p, q, b, x)) - radius
        if (f_a < 0.0) == (f_lo < 0.0) and (f_b < 0.0) == (f_hi < 0.0):
            lo, hi, f_lo, f_hi = a, b, f_a, f_b
            break
    g_lo, g_hi = f_lo, f_hi                 # (the values the secant uses: Illinois halves them)
    kept, step = 0, 0
    while not _same_point(p, q, lo, hi):
        step += 1
        t = 0.5 * (lo + hi)
        if step % BISECT_EVERY != 0 and g_hi != g_lo:
            secant = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
            if lo < secant < hi:
                t = secant
        if t <= lo or t >= hi:
            break
        f = segment_distance(start, end, axis, put_on_edge(p, q, t, x)) - radius
        if (f < 0.0) == (f_lo < 0.0):
            lo, f_lo, g_lo = t, f, f
            if kept == -1:
                g_hi *= 0.5
            kept = -1
        else:
            hi, f_hi, g_hi = t, f, f
            if kept == 1:
                g_lo *= 0.5
            kept = 1
    return lo if abs(f_lo) <= abs(f_hi) else hi


@inlined
def _same_point(p, q, a, b):
    """Whether parameters a and b of the edge p -> q (3,) give the same point (``put_on_edge``): a bracket
    that narrow has found the crossing as closely as a point can be placed."""
    for k in range(3):
        if p[k] + a * (q[k] - p[k]) != p[k] + b * (q[k] - p[k]):
            return False
    return True


@helper
def _guess(p, q, start, end, axis, radius):
    """Where p -> q (3,) meets the bit's surface, in closed form: a root in [0, 1] of |p + t (q - p) -
    axis line|^2 = r^2 whose point projects inside the travel, else of |p + t (q - p) - c|^2 = r^2 with
    c the end of the travel it lies beyond; -1 where none is found."""
    dx, dy, dz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    wx, wy, wz = p[0] - start[0], p[1] - start[1], p[2] - start[2]
    length2 = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]
    d_along, w_along = (dx * axis[0] + dy * axis[1] + dz * axis[2]), (wx * axis[0] + wy * axis[1] + wz * axis[2])
    a = dx * dx + dy * dy + dz * dz - d_along * d_along / length2
    b = 2.0 * (wx * dx + wy * dy + wz * dz - w_along * d_along / length2)
    c = wx * wx + wy * wy + wz * wz - w_along * w_along / length2 - radius * radius
    for t in _quadratic_roots(a, b, c):
        along = (w_along + t * d_along) / length2
        if 0.0 <= t <= 1.0 and 0.0 <= along <= 1.0:
            return t
    for beyond_end in (False, True):          # (the round ends)
        cap = end if beyond_end else start
        ex, ey, ez = p[0] - cap[0], p[1] - cap[1], p[2] - cap[2]
        for t in _quadratic_roots(dx * dx + dy * dy + dz * dz, 2.0 * (ex * dx + ey * dy + ez * dz),
                                  ex * ex + ey * ey + ez * ez - radius * radius):
            along = (w_along + t * d_along) / length2
            if 0.0 <= t <= 1.0 and (along > 1.0 if beyond_end else along < 0.0):
                return t
    return -1.0


@helper
def _quadratic_roots(a, b, c):
    """The real roots (two, equal where one; -1, -1 where none) of a t^2 + b t + c (a > 0), each computed
    without cancellation."""
    disc = b * b - 4.0 * a * c
    if a <= 0.0 or disc < 0.0:
        return -1.0, -1.0
    u = -0.5 * (b + math.copysign(math.sqrt(disc), b))
    if u == 0.0:
        return 0.0, 0.0
    return u / a, c / u
