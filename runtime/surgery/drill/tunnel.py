"""A tunnel: the wall on the bit's surface from one rim loop up to the next (an entry to an exit), or to
the tip's pole (a blind hole), in one compiled call (``_tunnel_grid``).

Its rows lie in rings at the columns' angles (``step`` apart around the axis: the rim's resolution), the
rings between the two loops' heights about ``axial`` apart along the cylinder, where the bit's surface is
straight (the mesh's resolution along the axis: ``budget.axial_step``), and ``step`` apart on its round
ends, which curve; ring i's rows blend the rim rows nearest in angle on the two loops
(``bit_surface.nearest_rows``) by its place between them. The loops get wall rows of their own (the rim's
points, other normals), each zipped to the nearest ring by angle (``strips.zip_rings``), the rings between
as a grid. A tunnel may also run down from a loop to the back's pole (the bit started inside the model).
Faces are wound to face the axis (in (θ, σ), counter-clockwise faces away from it: ∂θ × ∂σ is the
outward radial) where the solid they bound lies outside the bit as the input's faces wind it outward,
else the other way (an inward-wound shell: ``wall.py``).
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, F2, I1, b1, f8, helper, i8, kernel, record
from .bit_surface import Frame, Loop, _surface_points, modulo_turn, nearest_rows
from .patch import Patch
from .strips import grid, zip_rings

#: the numba types of a ``Loop`` as ``_tunnel_grid`` takes it (``_loop_record``) and of a ``Frame``
LOOP, FRAME = record(I1, I1, F1, F1, F1), record(F1, F2, f8, f8, f8)


def tunnel(patch: Patch, frame: Frame, a: Loop | None, b: Loop | None, step: float, axial: float, facing: bool,
           face_source: int) -> None:
    """Add the tunnel from loop a up to loop b to the patch, its faces from ``face_source``: a None is the
    back's pole (the wall runs down from b to it), b None the tip's; ``facing``: its faces face the axis
    (else away from it). Rings ``axial`` apart along the cylinder, ``step`` on the round ends."""
    upward = a is not None                  # (built from a up to b, or from b down to the back's pole)
    loop, other = (a, b) if upward else (b, None)
    pole_sigma = frame.top if upward else frame.bottom
    points, row_points, row_parents, row_t, faces, last = _tunnel_grid(
        _loop_record(loop), loop.winding, _loop_record(loop if other is None else other),
        0 if other is None else other.winding, other is not None,
        (frame.start, frame.axes, frame.length, frame.r, pole_sigma), step, axial, patch.n_points, patch.n_rows)
    patch.add_points(points)
    patch.new_rows(row_points, row_parents[:, 0], row_parents[:, 1], row_t)
    if other is None:                   # the last ring closed at the pole
        pole = _pole_row(patch, frame, pole_sigma, loop)
        faces = np.concatenate([faces, np.column_stack([np.roll(last, -1), last, np.full(len(last), pole)])])
    if facing != upward:                # (built downward, the grid faces away from the axis)
        faces = faces[:, [0, 2, 1]]
    patch.add_faces(faces, face_source)


def _loop_record(loop: Loop) -> tuple:
    return loop.rows, loop.points, loop.theta, loop.sigma, loop.unwrapped


@kernel((LOOP, i8, LOOP, i8, b1, FRAME, f8, f8, i8, i8), cost=2.0, fused=True)
def _tunnel_grid(a, a_winding, b, b_winding, has_b, frame, step, axial, first_point, first_row):
    """The tunnel's points, rows and faces from loop a to loop b (``has_b``; else to a pole's height
    ``pole``, above a or below it), loops as ``_loop_record`` gives them (with their windings), ``frame``
    (start, axes, length, r, pole) a ``Frame``'s; columns ``step`` apart around the axis, rings spaced
    evenly in ``_ring_measure`` (``axial`` apart on the cylinder, ``step`` on the round ends); new points
    and rows numbered from ``first_point`` and ``first_row``.

    Returns (points (p, 3); the new rows' points (r,), parents (r, 2) and t (r,) (``Patch.new_rows``);
    faces (G, 3), facing the axis when b (or the pole) lies above a; the last ring's rows (c,): b's, or
    the ring next to the pole)."""
    start, axes, length, r, top = frame
    count = max(8, int(math.ceil(2.0 * math.pi * r / step)))
    columns = np.empty(count)                       # the rings' angles, step apart
    for c in range(count):
        columns[c] = -math.pi + c * (2.0 * math.pi / count)
    low = _height_at(a, columns)
    high = _height_at(b, columns) if has_b else np.full(count, top)
    low_measure, high_measure = np.empty(count), np.empty(count)
    span = 0.0
    for c in range(count):
        low_measure[c] = _ring_measure(low[c], length, step, axial)
        high_measure[c] = _ring_measure(high[c], length, step, axial)
        span = max(span, abs(high_measure[c] - low_measure[c]))
    rings = max(1, int(math.ceil(span))) - 1       # (between the loops)
    ra = nearest_rows(a[2], a[0], columns)
    rb = nearest_rows(b[2], b[0], columns) if has_b else ra
    n_a, n_b = a[0].shape[0], b[0].shape[0] if has_b else 0
    n_rows = n_a + rings * count + n_b
    row_points, row_parents, row_t = np.empty(n_rows, np.int64), np.empty((n_rows, 2), np.int64), np.zeros(n_rows)
    # the loops' own rows (copies of the rim rows: t = 0), a's first, b's last
    for i in range(n_a):
        row_points[i], row_parents[i, 0], row_parents[i, 1] = a[1][i], a[0][i], a[0][i]
    for i in range(n_b):
        j = n_rows - n_b + i
        row_points[j], row_parents[j, 0], row_parents[j, 1] = b[1][i], b[0][i], b[0][i]
    theta, sigma = np.empty(rings * count), np.empty(rings * count)
    inner = np.empty((rings, count), np.int64)
    for i in range(rings):
        w = (i + 1) / (rings + 1)
        for c in range(count):
            k = i * count + c
            theta[k] = columns[c]
            sigma[k] = _ring_height((1.0 - w) * low_measure[c] + w * high_measure[c], length, step, axial)
            row_points[n_a + k], row_parents[n_a + k, 0], row_parents[n_a + k, 1] = first_point + k, ra[c], rb[c]
            row_t[n_a + k] = w if has_b else 0.0
            inner[i, c] = first_row + n_a + k
    points = _surface_points(theta, sigma, start, axes, length, r)
    bottom_rows, bottom_angles = _ring(first_row, a[4], a_winding)
    if rings:       # a's rows zipped to the first ring, the rings as a grid
        strips = [zip_rings(bottom_rows, bottom_angles, inner[0].copy(), columns), grid(inner)]
        last_rows, last_angles = inner[rings - 1].copy(), columns
    else:
        strips = [np.empty((0, 3), np.int64)]
        last_rows, last_angles = bottom_rows, bottom_angles
    if has_b:
        top_rows, top_angles = _ring(first_row + n_rows - n_b, b[4], b_winding)
        strips.append(zip_rings(last_rows, last_angles, top_rows, top_angles))
        last_rows = top_rows
    total = 0
    for s in strips:
        total += s.shape[0]
    faces, at = np.empty((total, 3), np.int64), 0
    for s in strips:
        for i in range(s.shape[0]):
            faces[at, 0], faces[at, 1], faces[at, 2] = s[i, 0], s[i, 2], s[i, 1]      # (to face the axis)
            at += 1
    return points, row_points, row_parents, row_t, faces, last_rows


@helper
def _ring_measure(sigma, length, step, axial):
    """How many ring spacings height σ lies from the cylinder's start: σ / ``axial`` on the cylinder
    (0 <= σ <= ``length``), each round end's arc in ``step``s (continuous, increasing; ``_ring_height``
    inverts it)."""
    if sigma < 0.0:
        return sigma / step
    if sigma > length:
        return length / axial + (sigma - length) / step
    return sigma / axial


@helper
def _ring_height(measure, length, step, axial):
    """The height σ of a ``_ring_measure``."""
    if measure < 0.0:
        return measure * step
    if measure > length / axial:
        return length + (measure - length / axial) * step
    return measure * axial


@helper
def _height_at(loop, theta):
    """σ (k,) of a loop (``_loop_record``) at angles θ (k,): linear in angle between the corners nearest
    below and above each (around the circle)."""
    angles, heights = loop[2], loop[3]
    turn, n = 2.0 * math.pi, angles.shape[0]
    out = np.empty(theta.shape[0])
    for i in range(theta.shape[0]):
        below, above, gap_below, gap_above = 0, 0, np.inf, np.inf
        for j in range(n):
            ahead = modulo_turn(angles[j] - theta[i])       # (in [0, 2π): how far on the corner is)
            if ahead <= gap_above:
                above, gap_above = j, ahead
            if turn - ahead < gap_below or (ahead == 0.0 and gap_below > 0.0):
                below, gap_below = j, (0.0 if ahead == 0.0 else turn - ahead)
        span = gap_below + gap_above
        w = gap_below / span if span > 0.0 else 0.0
        out[i] = (1.0 - w) * heights[below] + w * heights[above]
    return out


@helper
def _ring(first, unwrapped, winding):
    """(rows, unwrapped angles) of a winding loop's own wall rows (numbered from ``first`` in the loop's
    order), in the direction of increasing angle."""
    n = unwrapped.shape[0]
    rows, angles = np.empty(n, np.int64), np.empty(n)
    for i in range(n):
        j = i if winding > 0 else n - 1 - i
        rows[i], angles[i] = first + j, unwrapped[j]
    return rows, angles


def _pole_row(patch: Patch, frame: Frame, sigma: float, loop: Loop) -> int:
    """The row at the bit's tip, blended evenly from six rows spread around the loop it closes (a chain
    of blends: the rows between are used by no face, and dropped)."""
    picks = [loop.rows[i] for i in np.linspace(0, len(loop.rows) - 1, 6).astype(int)]
    point = patch.add_point(frame.point(0.0, sigma))
    row = picks[0]
    for i, r in enumerate(picks[1:], start=2):
        row = patch.new_row(point, row, r, 1.0 / i)
    return row
