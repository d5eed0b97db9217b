"""What a drill will make, found before it runs from the faces near the bit: the wall's step along the axis
(``axial_step``) and an upper bound on the new vertices (``new_vertex_bound``), which ``api.py`` checks
against its cap and gives out (``predicted_new_vertices``). One pass over the faces near the bit
(``near_summary``), reading each face's corners in place.

Where the bit's surface crosses a face (counted for every face with a corner outside the bit and a
point within its radius by the corners' bound: an upper bound), the refinement bisects it until the
faces it crosses are at most ``step`` long (``refine.py``), then the rim takes a vertex on each edge it
crosses. A face's share of the curve where the surface meets it is at most its perimeter, and at most
that of the plane's section of the bit (a convex set: its boundary within the triangle is shorter than
either's), which is at most π times its diameter, min(L + 2r, 2r / sin α) (the section of a cylinder by
a plane at an angle α to its axis is an ellipse of semi-axes r and r / sin α). The refined faces along
that curve are about a step long, and bisection reaches them from a face's own size in
2 log2(longest / step) rounds, each adding a few vertices around a crossing: so the refinement and the
rim make at most about ``PER_STEP`` rows per step of curve and ``PER_ROUND`` per round of each face
crossed, ``SHORT`` on a face no longer than a step (rows: a seam's copies count apart, two at a point
at most on a manifold edge).

The walls: each loop of the rim gets rows of its own (as many as the rim has), a tunnel's rings hold a
column per step around the axis (``tunnel.py``), ``axial`` apart along the travel and a step apart on
its round ends, and a surface crossing the axis (or its round ends) makes one loop, so the faces the
extended axis pierces bound the loops; a fill (a loop that does not wind around the axis) has at most
a column per step across it for each of its corners, and no more rows than the bit's surface holds.

The constants are measured with a margin: on random meshes, radii from 1e-3 to half a model's size and
down to the smallest radius, the bound exceeds the drill's count, by 1.3x to 40x
(tests/surgery/test_drill_edges.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, F2, I1, I2, b1, f8, helper, inlined, kernel
from .bit import NEAREST_CORNER

#: the rows the refinement and the rim make per step of the curve where the bit's surface meets the
#: faces, at most (measured: up to about 5 on meshes of any resolution, at any radius; twice that)
PER_STEP = 10.0
#: the rows per bisection round of each face the surface crosses, at most (a round adds a vertex or two
#: on each side of the crossing, and their seam copies)
PER_ROUND = 8.0
#: the rows the rim makes on a face no longer than a step (not refined): its crossed edges' points
SHORT = 4.0
#: the entries of ``near_summary``: the faces the surface crosses that are longer than a step (refined),
#: no longer (``SHORT``); the curve on the refined ones, in steps; their bisection rounds; the faces the
#: extended axis pierces; the median longest edge of the faces crossed (0 for none)
LONG, SHORT_FACES, CURVE_STEPS, ROUNDS, PIERCED, MEDIAN_LONGEST = range(6)


@kernel((F2, I2, I1, F1, F1, f8, f8, b1), cost=0.3)
def near_summary(positions, faces, near, start, end, radius, step, wall):
    """What ``new_vertex_bound`` and ``axial_step`` need of the faces ``near`` (k,) (rows of ``faces``
    (m, 3) over ``positions`` (n, 3)) for the bit of ``radius`` around start -> end (3,) and its rim
    ``step``: (6,) float64 indexed by ``LONG`` ... ``MEDIAN_LONGEST`` (module docstring; ``PIERCED`` and
    ``MEDIAN_LONGEST`` only for a ``wall``)."""
    out = np.zeros(6)
    axis = end - start
    length = math.sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2])
    back, tip = start - (radius / length) * axis, end + (radius / length) * axis    # (the axis through its ends)
    inverse = 1.0 / (length * length)
    longest = np.empty(near.shape[0])
    n_crossed = 0
    for i in range(near.shape[0]):
        p, q, r = faces[near[i], 0], faces[near[i], 1], faces[near[i], 2]
        # squared distances from the travel and its line, edges' squared lengths: roots only where needed
        da, la = _from_travel(positions, p, start, axis, inverse)
        db, lb = _from_travel(positions, q, start, axis, inverse)
        dc, lc = _from_travel(positions, r, start, axis, inverse)
        edge = math.sqrt(max(_between(positions, p, q), max(_between(positions, q, r), _between(positions, r, p))))
        reach = radius + NEAREST_CORNER * edge
        if min(da, min(db, dc)) >= reach * reach:
            continue                        # (every point of the face outside the bit: as ``surface_crosses``)
        # (a face the axis line passes through has a corner that near it)
        near_axis = wall and min(la, min(lb, lc)) <= (NEAREST_CORNER * edge) ** 2
        inside = max(da, max(db, dc)) <= radius * radius
        if inside and not near_axis:
            continue
        a, b, c = positions[p], positions[q], positions[r]       # (views: only for the few faces left)
        if near_axis and _pierces(back, tip, a, b, c):
            out[PIERCED] += 1.0
        if inside:
            continue
        # (crossed, or within a corner's reach of the surface: counted as crossed, an upper bound)
        longest[n_crossed] = edge
        n_crossed += 1
        if edge <= step:
            out[SHORT_FACES] += 1.0
            continue
        out[LONG] += 1.0
        out[ROUNDS] += math.ceil(2.0 * math.log2(edge / step))
        perimeter = math.sqrt(_between(positions, p, q)) + math.sqrt(_between(positions, q, r)) + \
            math.sqrt(_between(positions, r, p))
        out[CURVE_STEPS] += min(perimeter, math.pi * _section(a, b, c, axis, length, radius)) / step
    if wall and n_crossed:
        out[MEDIAN_LONGEST] = np.median(longest[:n_crossed])
    return out


@inlined
def _between(positions, p, q):
    """The squared distance between rows p and q of ``positions`` (n, 3)."""
    dx, dy, dz = positions[q, 0] - positions[p, 0], positions[q, 1] - positions[p, 1], positions[q, 2] - positions[p, 2]
    return dx * dx + dy * dy + dz * dz


@inlined
def _from_travel(positions, p, start, axis, inverse):
    """The squared distances of row p of ``positions`` (n, 3) from the travel start -> start + ``axis``
    (3,) (``inverse``: 1 / its squared length) (as ``bit.segment_distance``) and from its line (rows
    read in place: no view of a row in the loop over faces)."""
    wx, wy, wz = positions[p, 0] - start[0], positions[p, 1] - start[1], positions[p, 2] - start[2]
    t = (wx * axis[0] + wy * axis[1] + wz * axis[2]) * inverse
    lx, ly, lz = wx - t * axis[0], wy - t * axis[1], wz - t * axis[2]
    along = min(max(t, 0.0), 1.0)
    dx, dy, dz = wx - along * axis[0], wy - along * axis[1], wz - along * axis[2]
    return dx * dx + dy * dy + dz * dz, lx * lx + ly * ly + lz * lz


@helper
def _section(a, b, c, axis, length, radius):
    """The diameter bound of the section of the bit (travel ``axis`` (3,) of ``length``, ``radius``) by
    the plane of triangle abc: min(L + 2r, 2r / sin α), α the plane's angle to the axis."""
    ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    sine = abs(nx * axis[0] + ny * axis[1] + nz * axis[2]) / (norm * length) if norm > 0.0 else 0.0
    section = length + 2.0 * radius
    return 2.0 * radius / sine if 2.0 * radius < sine * section else section


@helper
def _pierces(p, q, a, b, c):
    """Whether the segment p -> q (3,) meets triangle abc (its ends on either side of the plane, or on
    it, and the three volumes it makes with the edges of one sign, or zero: edges and corners count)."""
    sp, sq = _volume(p, a, b, c), _volume(q, a, b, c)
    if (sp > 0.0 and sq > 0.0) or (sp < 0.0 and sq < 0.0):
        return False
    u, v, w = _volume(p, q, a, b), _volume(p, q, b, c), _volume(p, q, c, a)
    return (u >= 0.0 and v >= 0.0 and w >= 0.0) or (u <= 0.0 and v <= 0.0 and w <= 0.0)


@helper
def _volume(p, a, b, c):
    """Six times the signed volume of the tetrahedron p, a, b, c (3,) each."""
    ax, ay, az = a[0] - p[0], a[1] - p[1], a[2] - p[2]
    bx, by, bz = b[0] - p[0], b[1] - p[1], b[2] - p[2]
    cx, cy, cz = c[0] - p[0], c[1] - p[1], c[2] - p[2]
    return ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)


def axial_step(summary, step: float) -> float:
    """The wall's step along the bit's axis: the median longest edge of the faces the bit's surface
    crosses (the mesh's resolution where the hole is), at least ``step`` (the rim's)."""
    return max(step, float(summary[MEDIAN_LONGEST]))


def new_vertex_bound(summary, bit, step: float, axial: float, wall: bool) -> int:
    """An upper bound on the new vertices of a drill whose faces near the bit have ``summary``
    (``near_summary``), its rim ``step`` and the wall's ``axial`` step (module docstring)."""
    long, short, curve, rounds, pierced, median = summary.tolist()
    if long + short == 0.0:
        return 0
    rim = PER_STEP * curve + PER_ROUND * rounds + SHORT * short
    if not wall:
        return int(math.ceil(rim))
    radius, travel = bit.radius, math.dist(bit.start, bit.end)
    columns = max(8, math.ceil(2.0 * math.pi * radius / step))
    loops = max(1.0, pierced)
    rings = math.ceil(loops / 2.0) * (math.ceil(travel / axial) + math.ceil(math.pi * radius / step)) + 2.0 * loops
    # a fill: chains about a step apart across it, each with a row per corner of the rim along it (about
    # two per step of curve on a refined face, one per short face), and no more rows than the bit's
    # surface holds at a step across and half the rim's spacing along
    points = 2.0 * curve + short
    area = 2.0 * math.pi * radius * travel + 4.0 * math.pi * radius * radius
    fills = min(0.5 * columns * points, area / (step * 0.5 * min(step, median)))
    return int(math.ceil(2.0 * rim + columns * rings + 6.0 * loops + fills))
