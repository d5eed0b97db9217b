"""The region a stroke may tear: where the blade swept between t_i and t_{i+1}.

The blade is the segment a0 -> b0 at t_i and a1 -> b1 at t_{i+1}; what it swept lies in the convex hull
of those four points (a tetrahedron, or a flat quadrilateral when the blade moved in its own plane).
The path of a stroke must stay within ``margin`` of that hull, with margin = |S_{i+1} - S_i| plus the
longest edge of the two faces the blade hit: the surface between two nearby hits bulges out of the
hull by about a face where the mesh is coarse or curved, never by more than the stroke itself -- a
path that goes further is a detour round an obstacle (an existing slit, a fold), which the blade
never touched.

Where the stroke is long or the mesh coarse next to a thin part (a limb whose radius is about the
margin), the whole section may lie within the margin: where an existing opening stops the near way
(a slit the path cannot cross there), the way round the far side of the limb would pass. So such a
path also may not go beyond the blade's reach (``_beyond_the_blade``): in the tear plane, it may not
cross the line of the blade beyond its tip, as the way round the far side does, coming back under the
tip, where the blade never was. (Only there: a tilted blade's line beyond its tip can come out through
the skin the stroke tears, on a bent or thin part, and a blade that passes right through a limb
reaches its far side.)
"""
import math

import numpy as np

from ..._shared.jit import helper
from ...algebra.vec3 import _distance
from .records import POINT


# 3-vectors as tuples of floats here: numba keeps them in registers, where a (3,) array would be a
# heap allocation (this runs for every node the walk pushes)
@helper
def _t(a):
    return a[0], a[1], a[2]


@helper
def _tsub(u, v):
    return u[0] - v[0], u[1] - v[1], u[2] - v[2]


@helper
def _tdot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@helper
def _tcross(u, v):
    return u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]


@helper
def _tdistance(u, v):
    d = _tsub(u, v)
    return math.sqrt(_tdot(d, d))


@helper
def _segment_distance(p, a, b):
    """Distance from p to the segment a b (tuples)."""
    d = _tsub(b, a)
    dd = _tdot(d, d)
    t = 0.0 if dd == 0.0 else min(max(_tdot(_tsub(p, a), d) / dd, 0.0), 1.0)
    return _tdistance(p, (a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]))


@helper
def _triangle_distance(p, a, b, c):
    """Distance from point p to the triangle a b c (tuples), by the Voronoi regions of its corners,
    edges and face; a triangle of zero area works (as its edges)."""
    ab, ac, ap = _tsub(b, a), _tsub(c, a), _tsub(p, a)
    d1, d2 = _tdot(ab, ap), _tdot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return _tdistance(p, a)
    bp = _tsub(p, b)
    d3, d4 = _tdot(ab, bp), _tdot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return _tdistance(p, b)
    cp = _tsub(p, c)
    d5, d6 = _tdot(ab, cp), _tdot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return _tdistance(p, c)
    vc, vb, va = d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:              # nearest on edge ab
        return _segment_distance(p, a, b)
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:              # on edge ac
        return _segment_distance(p, a, c)
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:    # on edge bc
        return _segment_distance(p, b, c)
    total = va + vb + vc
    if not total > 0.0:                                   # zero area: its edges hold all of it
        return min(_segment_distance(p, a, b), min(_segment_distance(p, b, c), _segment_distance(p, a, c)))
    v, w = vb / total, vc / total                         # inside the face
    return _tdistance(p, (a[0] + v * ab[0] + w * ac[0], a[1] + v * ab[1] + w * ac[1],
                          a[2] + v * ab[2] + w * ac[2]))


@helper
def _outside(p, region):
    """How far point ``p`` (a tuple (x, y, z)) lies outside the convex hull of the four rows of ``region`` (4, 3): 0
    inside.

    Inside a tetrahedron every face sees p on the side of its fourth corner; outside (or for a flat
    hull, whose four triangles cover it) the distance is the smallest to the four triangles."""
    q = (_t(region[0]), _t(region[1]), _t(region[2]), _t(region[3]))
    inside = True
    for skip in range(4):
        a, b, c = q[(skip + 1) % 4], q[(skip + 2) % 4], q[(skip + 3) % 4]
        normal = _tcross(_tsub(b, a), _tsub(c, a))
        if not _tdot(normal, _tsub(p, a)) * _tdot(normal, _tsub(q[skip], a)) > 0.0:
            inside = False
            break
    if inside:
        return 0.0
    best = np.inf
    for skip in range(4):
        best = min(best, _triangle_distance(p, q[(skip + 1) % 4], q[(skip + 2) % 4], q[(skip + 3) % 4]))
    return best


@helper
def _margin(wpos, wfaces, hit_faces, s_pos, t_pos):
    """|S_{i+1} - S_i| plus the longest edge of the two hit faces (module docstring)."""
    longest = 0.0
    for f in hit_faces:
        for k in range(3):
            longest = max(longest, _distance(wpos[wfaces[f, k]], wpos[wfaces[f, (k + 1) % 3]]))
    return _distance(s_pos, t_pos) + longest



@helper
def _crosses_ray(points, chain, origin, direction, normal, snap):
    """Whether the polyline ``points[chain]`` (rows of x, y, z from column ``POINT``: the walk's nodes)
    crosses the ray from ``origin`` along the unit ``direction`` (tuples), both in the plane of unit
    ``normal``, further than ``snap`` from the origin (a vertex on the ray counts on its positive side:
    the half-open rule, so that a path through a point of the ray counts once)."""
    side = _tcross(normal, direction)
    prev_u, prev_v = 0.0, 0.0
    for r in range(chain.shape[0]):
        q = chain[r]
        d = (points[q, POINT] - origin[0], points[q, POINT + 1] - origin[1], points[q, POINT + 2] - origin[2])
        u, v = _tdot(d, direction), _tdot(d, side)
        if r > 0 and (prev_v < 0.0) != (v < 0.0):
            if prev_u + (u - prev_u) * prev_v / (prev_v - v) > snap:
                return True
        prev_u, prev_v = u, v
    return False


@helper
def _beyond_the_blade(points, chain, plane, region, snap):
    """Whether the path ``points[chain]`` (the walk's node floats: x, y, z from column ``POINT``) passes
    beyond the reach of the blade: in the tear ``plane`` (4,), across the line of a blade position of
    ``region`` (a0, b0, a1, b1) beyond its tip (a blade that lies in the plane, within ``snap`` of it)."""
    normal = _t(plane)
    for end in range(2):
        handle, tip = _t(region[2 * end]), _t(region[2 * end + 1])
        if not (abs(_tdot(normal, handle) - plane[3]) <= snap and abs(_tdot(normal, tip) - plane[3]) <= snap):
            continue
        blade = _tsub(tip, handle)
        length = math.sqrt(_tdot(blade, blade))
        direction = (blade[0] / length, blade[1] / length, blade[2] / length)
        if _crosses_ray(points, chain, tip, direction, normal, snap):
            return True
    return False
