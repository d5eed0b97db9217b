"""Coordinates on the bit's surface (``Frame``) and the rims' loops in them (``Loop``), for the walls.

The bit's surface is a surface of revolution: a point of it is (θ, σ), its angle around the axis and
its height along the profile (the back hemisphere for σ < 0, the cylinder for 0 <= σ <= L, the tip
hemisphere for σ > L, σ measured as arc length).
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, F2, I1, f8, helper, kernel


class Frame:
    """The bit's axis frame: unit axis u, e1, e2 across it (``axes`` (3, 3): the three as rows), travel
    length L, radius r."""

    def __init__(self, bit):
        self.start, self.end, self.r = bit.start, bit.end, bit.radius
        self.axes, self.length = _axes(bit.start, bit.end)
        self.u, self.e1, self.e2 = self.axes
        self.top = self.length + 0.5 * math.pi * self.r          # σ of the tip's pole
        self.bottom = -0.5 * math.pi * self.r                     # σ of the back's pole

    def coordinates(self, x) -> tuple:
        """(θ, σ) of points x (k, 3) on the bit's surface."""
        w = x - self.start
        s, a, b = w @ self.u, w @ self.e1, w @ self.e2
        theta = np.arctan2(b, a)
        radial = np.hypot(a, b)
        sigma = np.where(s > self.length, self.length + self.r * np.arctan2(s - self.length, radial),
                         np.where(s < 0.0, -self.r * np.arctan2(-s, radial), s))
        return theta, sigma

    def point(self, theta: float, sigma: float) -> np.ndarray:
        """The surface point (3,) at (θ, σ)."""
        return self.points(np.array([theta]), np.array([sigma]))[0]

    def points(self, theta, sigma) -> np.ndarray:
        """The surface points (k, 3) at angles θ (k,) and heights σ (k,) (``_surface_points``)."""
        return _surface_points(np.ascontiguousarray(theta, np.float64), np.ascontiguousarray(sigma, np.float64),
                               self.start, self.axes, self.length, self.r)

    def axis_point(self, sigma: float) -> np.ndarray:
        """The point of the axis at the height of σ (inside the bit)."""
        if sigma > self.length:
            return self.end + self.r * math.sin(min((sigma - self.length) / self.r, 0.5 * math.pi)) * self.u
        if sigma < 0.0:
            return self.start - self.r * math.sin(min(-sigma / self.r, 0.5 * math.pi)) * self.u
        return self.start + sigma * self.u


@kernel((F1, F1, F1, F2, f8, f8), cost=0.2)
def _surface_points(theta, sigma, start, axes, length, r):
    """The surface points (k, 3) at θ (k,), σ (k,): on the cylinder, or on a round end beyond it (the
    angle φ up the end's quarter circle from the rim). ``axes`` (3, 3): u, e1, e2 as rows."""
    out = np.empty((theta.shape[0], 3))
    for i in range(theta.shape[0]):
        s = sigma[i]
        phi, along = 0.0, min(max(s, 0.0), length)
        if s > length:
            phi = min((s - length) / r, 0.5 * math.pi)
        elif s < 0.0:
            phi = -min(-s / r, 0.5 * math.pi)
        up, across = r * math.sin(phi), r * math.cos(phi)
        c, d = across * math.cos(theta[i]), across * math.sin(theta[i])
        for k in range(3):
            out[i, k] = start[k] + (along + up) * axes[0, k] + c * axes[1, k] + d * axes[2, k]
    return out


class Loop:
    """A rim loop: its rows (one per corner, in the boundary's direction), points, (θ, σ) and θ unwrapped
    along it, its winding about the axis (``loops`` makes them)."""

    def __init__(self, rows, points, theta, sigma, unwrapped, winding: int):
        self.rows, self.points = np.asarray(rows, np.int64), points
        self.theta, self.sigma, self.unwrapped, self.winding = theta, sigma, unwrapped, int(winding)


@kernel((F1, F1), cost=0.1)
def _axes(start, end):
    """(the unit axis u of start -> end, e1 = u x (the coordinate axis least along u), normalised, and
    e2 = u x e1, as rows (3, 3); the length of start -> end)."""
    axes = np.zeros((3, 3))
    length = math.sqrt((end[0] - start[0]) ** 2 + (end[1] - start[1]) ** 2 + (end[2] - start[2]) ** 2)
    for k in range(3):
        axes[0, k] = (end[k] - start[k]) / length
    least = 0
    for k in range(1, 3):
        if abs(axes[0, k]) < abs(axes[0, least]):
            least = k
    axes[1, (least + 1) % 3], axes[1, (least + 2) % 3] = axes[0, (least + 2) % 3], -axes[0, (least + 1) % 3]
    norm = math.sqrt(axes[1, 0] ** 2 + axes[1, 1] ** 2 + axes[1, 2] ** 2)
    for k in range(3):
        axes[1, k] /= norm
    for k in range(3):
        axes[2, k] = axes[0, (k + 1) % 3] * axes[1, (k + 2) % 3] - axes[0, (k + 2) % 3] * axes[1, (k + 1) % 3]
    return axes, length


def loops(frame: Frame, rows, points, positions, offsets) -> list:
    """The ``Loop``s of corners ``rows`` (L,) at ``points`` (L,) with ``positions`` (L, 3) on the bit's
    surface, loop i being [offsets[i], offsets[i + 1]) (``_loop_coordinates``)."""
    theta, sigma, unwrapped, winding = _loop_coordinates(positions, offsets, frame.start, frame.axes, frame.length,
                                                         frame.r)
    return [Loop(rows[i:j], points[i:j], theta[i:j], sigma[i:j], unwrapped[i:j], w)
            for i, j, w in zip(offsets[:-1].tolist(), offsets[1:].tolist(), winding.tolist())]


@kernel((F2, I1, F1, F2, f8, f8), cost=0.2)
def _loop_coordinates(x, offsets, start, axes, length, r):
    """(θ, σ) (L,) of points x (L, 3) on the bit's surface (``Frame``: start, axes, length, r); θ unwrapped
    (L,) along each loop [offsets[i], offsets[i + 1]) (each turn to the next corner taken in [-π, π)),
    and each loop's winding (k,): its turns' sum in whole turns."""
    n = x.shape[0]
    theta, sigma, unwrapped = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        s, a, b = 0.0, 0.0, 0.0
        for k in range(3):
            w = x[i, k] - start[k]
            s, a, b = s + w * axes[0, k], a + w * axes[1, k], b + w * axes[2, k]
        theta[i], radial = math.atan2(b, a), math.hypot(a, b)
        if s > length:
            sigma[i] = length + r * math.atan2(s - length, radial)
        elif s < 0.0:
            sigma[i] = -r * math.atan2(-s, radial)
        else:
            sigma[i] = s
    winding = np.empty(offsets.shape[0] - 1, np.int64)
    for loop in range(offsets.shape[0] - 1):
        first, last = offsets[loop], offsets[loop + 1]
        total = 0.0
        unwrapped[first] = theta[first]
        for j in range(first, last):
            following = j + 1 if j + 1 < last else first
            turn = modulo_turn(theta[following] - theta[j] + math.pi) - math.pi
            total += turn
            if j + 1 < last:
                unwrapped[j + 1] = unwrapped[j] + turn
        winding[loop] = round(total / (2.0 * math.pi))
    return theta, sigma, unwrapped, winding


@kernel((F1, I1, F1), cost=0.1)
def nearest_rows(angles, rows, theta):
    """For each of θ (k,), the row (of ``rows`` (n,), at ``angles`` (n,)) whose angle is nearest around the
    circle, the first on a tie (a loop has tens of corners and a tunnel asks once per column)."""
    out = np.empty(theta.shape[0], np.int64)
    for i in range(theta.shape[0]):
        best, gap = 0, np.inf
        for j in range(angles.shape[0]):
            g = abs(modulo_turn(angles[j] - theta[i] + math.pi) - math.pi)
            if g < gap:
                best, gap = j, g
        out[i] = rows[best]
    return out


@helper
def modulo_turn(x):
    """x % 2π, in [0, 2π) as Python's float modulo gives it, without numba's call to fmod where x lies
    within a turn or two of 0 (a difference of angles: the wall's inner loops ask tens of thousands)."""
    turn = 2.0 * math.pi
    if 0.0 <= x < turn:
        return x
    if -turn < x < 0.0:
        return x + turn            # (fmod gives x itself, then the modulo adds a turn)
    if turn <= x < 2.0 * turn:
        return x - turn            # (exact: x and the turn are within a factor of 2)
    return x % turn
