"""Coordinates on the bit's surface (``Frame``) and the rims' loops in them (``Loop``), for the walls.

The bit's surface is a surface of revolution: a point of it is (θ, σ), its angle around the axis and
its height along the profile (the back hemisphere for σ < 0, the cylinder for 0 <= σ <= L, the tip
hemisphere for σ > L, σ measured as arc length).
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, F2, I1, f8, kernel


def _cross(a, b) -> np.ndarray:
    """a x b of two (3,) vectors (``np.cross`` costs ~16 us a call here, for its generality; this ~1)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


class Frame:
    """The bit's axis frame: unit axis u, e1, e2 across it, travel length L, radius r."""

    def __init__(self, bit):
        self.start, self.end, self.r = bit.start, bit.end, bit.radius
        d = bit.end - bit.start
        self.length = float(np.linalg.norm(d))
        self.u = d / self.length
        helper = np.eye(3)[int(np.argmin(np.abs(self.u)))]
        self.e1 = _cross(self.u, helper)
        self.e1 /= np.linalg.norm(self.e1)
        self.e2 = _cross(self.u, self.e1)
        self.top = self.length + 0.5 * math.pi * self.r          # σ of the tip's pole
        self._axes = np.stack([self.u, self.e1, self.e2])

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
                               self.start, self._axes, self.length, self.r)

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
    """A rim loop: its rows (one per corner, in the boundary's direction), points, (θ, σ), winding."""

    def __init__(self, rows, points, theta, sigma):
        self.rows, self.points, self.sigma = np.asarray(rows, np.int64), points, sigma
        turns = np.diff(np.concatenate([theta, theta[:1]]))
        turns = (turns + math.pi) % (2 * math.pi) - math.pi
        self.unwrapped = theta[0] + np.concatenate([[0.0], np.cumsum(turns[:-1])])
        self.winding = int(round(turns.sum() / (2 * math.pi)))
        self.theta = np.ascontiguousarray(theta, np.float64)

    def height_at(self, theta: np.ndarray) -> np.ndarray:
        """σ of the loop at angles θ (linear between its corners, periodic)."""
        order = np.argsort(self.theta)
        t, s = self.theta[order], self.sigma[order]
        return np.interp(theta, np.concatenate([t - 2 * math.pi, t, t + 2 * math.pi]), np.tile(s, 3))

    def nearest_rows(self, theta) -> np.ndarray:
        """The loop's rows (k,) nearest in angle to each of θ (k,): of the rows at the nearest angle, the
        first in the loop's order (``_nearest``)."""
        return _nearest(self.theta, self.rows, np.ascontiguousarray(theta, np.float64))


@kernel((F1, I1, F1), cost=0.1)
def _nearest(angles, rows, theta):
    """For each of θ (k,), the row (of ``rows`` (n,), at ``angles`` (n,)) whose angle is nearest around the
    circle, the first on a tie (a loop has tens of corners and a tunnel asks once per column)."""
    out = np.empty(theta.shape[0], np.int64)
    for i in range(theta.shape[0]):
        best, gap = 0, np.inf
        for j in range(angles.shape[0]):
            g = abs((angles[j] - theta[i] + math.pi) % (2 * math.pi) - math.pi)
            if g < gap:
                best, gap = j, g
        out[i] = rows[best]
    return out
