"""Strips of wall triangles between two rings of rows around the bit (``zip_rings``, ``grid``) or two
chains of rows along a fill (``zip_chains``), advancing on the side whose next corner comes first."""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, I1, kernel


def grid(rings) -> np.ndarray:
    """The triangles between each ring of ``rings`` (k, c) and the next, all at the same angles (as
    ``zip_rings`` makes them: (a, a', b) then (a', b', b) at each column)."""
    lower, upper = rings[:-1], rings[1:]
    lower_next, upper_next = np.roll(lower, -1, axis=1), np.roll(upper, -1, axis=1)
    pairs = np.stack([np.stack([lower, lower_next, upper], axis=-1),
                      np.stack([lower_next, upper_next, upper], axis=-1)], axis=2)
    return pairs.reshape(-1, 3)


def zip_rings(ra, ua, rb, ub) -> np.ndarray:
    """Triangles (a, a', b) and (a, b', b) between two rings of rows, each once around the axis in the
    direction of increasing angle (``ua``, ``ub`` unwrapped; a rim may step back a little), advancing
    on the ring whose next corner comes first. Every edge of either ring is used once, whatever the
    angles: the strip is closed. In (θ, σ), with ring a below ring b, they are counter-clockwise.
    Returns (na + nb, 3) rows."""
    ua, ub = np.asarray(ua, np.float64), np.asarray(ub, np.float64)
    j = int(np.argmin(np.abs((ub - ua[0] + math.pi) % (2 * math.pi) - math.pi)))    # b starts near a
    rb = np.roll(np.asarray(rb, np.int64), -j)
    ub = np.concatenate([ub[j:], ub[:j] + 2 * math.pi])
    ub -= 2 * math.pi * round((ub[0] - ua[0]) / (2 * math.pi))
    ua, ub = np.append(ua, ua[0] + 2 * math.pi), np.append(ub, ub[0] + 2 * math.pi)
    return _zip(np.asarray(ra, np.int64), ua, rb, ub)


@kernel((I1, F1, I1, F1), cost=0.2)
def _zip(ra, ua, rb, ub):
    """``zip_rings``' merge: rows ra (na,), rb (nb,) and angles ua (na + 1,), ub (nb + 1,) (each ring's
    first again at the end, 2π on); (na + nb, 3) triangles."""
    na, nb = ra.shape[0], rb.shape[0]
    out = np.empty((na + nb, 3), np.int64)
    i = k = 0
    while i < na or k < nb:
        if k == nb or (i < na and ua[i + 1] <= ub[k + 1]):
            out[i + k, 0], out[i + k, 1], out[i + k, 2] = ra[i], ra[(i + 1) % na], rb[k % nb]
            i += 1
        else:
            out[i + k, 0], out[i + k, 1], out[i + k, 2] = ra[i % na], rb[(k + 1) % nb], rb[k]
            k += 1
    return out


def zip_chains(key, lower: list, upper: list) -> list:
    """Triangles (corner indices) between two chains from one corner to another, ``key`` (an angle or a
    height per corner) increasing along both, advancing the chain whose next corner comes first."""
    out, i, k = [], 0, 0
    while i < len(lower) - 1 or k < len(upper) - 1:
        if k == len(upper) - 1 or (i < len(lower) - 1 and key[lower[i + 1]] <= key[upper[k + 1]]):
            out.append((lower[i], lower[i + 1], upper[k]))
            i += 1
        else:
            out.append((lower[i], upper[k + 1], upper[k]))
            k += 1
    return [tri for tri in out if len(set(tri)) == 3]
