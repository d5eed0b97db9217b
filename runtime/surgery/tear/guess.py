"""A stroke's first guess of its tear plane and margin, on the whole surface (``splice.py`` picks the
stroke's patch with it; ``locate`` on the patch then confirms it or corrects it)."""
import math

import numpy as np

from ..._shared.jit import B1, F2, callee, f8, helper
from ...generated.kernels import plane_from_points
from ..bvh import BVH_ARRAYS, _first_hit, _near_box, _push_children
from .records import FROM_MISSES, OK


@helper
def _boundary_near(bvh, boundary, a, b, t_max, snap):
    """``locate._boundary_hit`` through the BVH: the flagged (``boundary`` (n,) bool) vertex within
    ``snap`` of segment a -> b with the smallest parameter t < t_max (then the lowest vertex id), as
    (vertex, t), or (-1, t_max). Only the leaves whose box the segment passes within ``snap`` of are
    read: a boundary vertex is a corner of a face in such a leaf, so a stroke costs what the blade
    passes, not the length of every slit made so far."""
    node_lo, node_hi, node_left, node_right, node_start, node_count, order, positions, faces = bvh
    d = b - a
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    best, best_t = -1, t_max
    stack = np.empty(128, np.int64)
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        if not _near_box(node_lo[node], node_hi[node], a, d, t_max, snap):
            continue
        if node_left[node] >= 0:
            stack, top = _push_children(stack, top, node_left[node], node_right[node])
            continue
        for i in range(node_start[node], node_start[node] + node_count[node]):
            for c in range(3):
                w = faces[order[i], c]
                if not boundary[w]:
                    continue
                p = positions[w]
                t = min(max(((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / dd, 0.0), 1.0)
                if (t < best_t or (best >= 0 and t == best_t and w < best)) and math.sqrt(
                        (a[0] + t * d[0] - p[0]) ** 2 + (a[1] + t * d[1] - p[1]) ** 2
                        + (a[2] + t * d[2] - p[2]) ** 2) <= snap:
                    best, best_t = w, t
    return best, best_t


@helper
def _distance(p, q):
    return math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2)


@callee((BVH_ARRAYS, B1, F2, f8, f8), cost=5.0)
def _guess(bvh, boundary, blades, snap, min_sine):
    """Where the blade meets the skin at both times, on the whole surface (snapped to a boundary
    vertex or a corner of the hit face as ``locate`` snaps), the plane through the first point and
    the blade at t_(i+1), and the margin of ``region.py`` with the hit faces' edges, widened
    (``locate`` may snap the points a little further).

    bvh : BVHArrays (as a tuple) of the whole surface ; boundary : (n,) bool the boundary flags of
    its vertices ; blades : (4, 3) handle and tip at t_i, then at t_(i+1) ; snap : absolute distance
    returns status (``records.OK``, or which position missed: FROM_MISSES, TO_MISSES), plane (4,) (zeros
    when the points and the blade are aligned: no plane), margin, hit faces (2,) (-1 where a boundary
    vertex was met instead)
    """
    positions, faces = bvh[7], bvh[8]
    points = np.empty((2, 3))
    hit_faces = np.full(2, -1, np.int64)
    longest = 0.0
    for i in range(2):
        a, b = blades[2 * i], blades[2 * i + 1]
        face, t = _first_hit(bvh, a, b)
        w, _ = _boundary_near(bvh, boundary, a, b, t if face >= 0 else 1.0, snap)
        if w >= 0:
            points[i] = positions[w]
            continue
        if face < 0:
            return FROM_MISSES + i, np.zeros(4), 0.0, hit_faces
        hit_faces[i] = face
        hit = a + t * (b - a)
        nearest, nearest_distance = 0, np.inf
        for c in range(3):
            distance = _distance(positions[faces[face, c]], hit)
            if distance < nearest_distance:
                nearest, nearest_distance = c, distance
            longest = max(longest, _distance(positions[faces[face, c]], positions[faces[face, c - 1]]))
        points[i] = positions[faces[face, nearest]] if nearest_distance <= snap else hit
    u0, u1, u2 = blades[2, 0] - points[0, 0], blades[2, 1] - points[0, 1], blades[2, 2] - points[0, 2]
    v0, v1, v2 = blades[3, 0] - points[0, 0], blades[3, 1] - points[0, 1], blades[3, 2] - points[0, 2]
    lu, lv = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2), math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
    plane = np.zeros(4)
    if lu > snap and lv > snap and math.sqrt(n0 * n0 + n1 * n1 + n2 * n2) > min_sine * lu * lv:
        plane[0], plane[1], plane[2], plane[3] = plane_from_points(points[0], blades[2], blades[3])
    return OK, plane, 1.25 * (_distance(points[0], points[1]) + longest) + 4.0 * snap, hit_faces
