"""Strips of wall triangles between two rings of rows around the bit (``zip_rings``, ``grid``) or two
chains of rows along a fill (``zip_chains``), advancing on the side whose next corner comes first."""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, I1, I2, kernel
from .bit_surface import modulo_turn


@kernel((I2,), cost=0.1)
def grid(rings):
    """The triangles between each ring of ``rings`` (k, c) and the next, all at the same angles (as
    ``zip_rings`` makes them: (a, a', b) then (a', b', b) at each column)."""
    k, c = rings.shape
    out = np.empty((2 * max(k - 1, 0) * c, 3), np.int64)
    at = 0
    for i in range(k - 1):
        for j in range(c):
            a, a_next, b, b_next = rings[i, j], rings[i, (j + 1) % c], rings[i + 1, j], rings[i + 1, (j + 1) % c]
            out[at, 0], out[at, 1], out[at, 2] = a, a_next, b
            out[at + 1, 0], out[at + 1, 1], out[at + 1, 2] = a_next, b_next, b
            at += 2
    return out


@kernel((I1, F1, I1, F1), cost=0.2)
def zip_rings(ra, ua, rb, ub):
    """Triangles (a, a', b) and (a, b', b) between two rings of rows ``ra`` (na,), ``rb`` (nb,), each once
    around the axis in the direction of increasing angle (``ua`` (na,), ``ub`` (nb,) unwrapped; a rim
    may step back a little), from the corner of b nearest a's first, advancing on the ring whose next
    corner comes first. Every edge of either ring is used once, whatever the angles: the strip is
    closed. In (θ, σ), with ring a below ring b, they are counter-clockwise. Returns (na + nb, 3) rows."""
    na, nb, turn = ra.shape[0], rb.shape[0], 2 * math.pi
    j, gap = 0, np.inf
    for i in range(nb):                                       # b starts near a
        g = abs(modulo_turn(ub[i] - ua[0] + math.pi) - math.pi)
        if g < gap:
            j, gap = i, g
    # each ring's angles with its first again at the end, one turn on; b's from its corner j
    a_angles, b_angles, b_rows = np.empty(na + 1), np.empty(nb + 1), np.empty(nb, np.int64)
    a_angles[:na], a_angles[na] = ua, ua[0] + turn
    for i in range(nb):
        b_rows[i] = rb[(i + j) % nb]
        b_angles[i] = ub[i + j] if i + j < nb else ub[i + j - nb] + turn
    b_angles[:nb] -= turn * round((b_angles[0] - ua[0]) / turn)
    b_angles[nb] = b_angles[0] + turn
    out = np.empty((na + nb, 3), np.int64)
    i = k = 0
    while i < na or k < nb:
        if k == nb or (i < na and a_angles[i + 1] <= b_angles[k + 1]):
            out[i + k, 0], out[i + k, 1], out[i + k, 2] = ra[i], ra[(i + 1) % na], b_rows[k % nb]
            i += 1
        else:
            out[i + k, 0], out[i + k, 1], out[i + k, 2] = ra[i % na], b_rows[(k + 1) % nb], b_rows[k]
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
