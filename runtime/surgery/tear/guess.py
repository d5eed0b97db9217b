"""A stroke's first guess of its tear plane and margin, on the whole surface (``splice.py`` picks the
stroke's patch with it; ``locate`` on the patch then confirms it or corrects it). The blade meets the
surface as ``locate`` finds it (``locate._meet``) and the plane is ``locate``'s first choice, on the
whole surface's vertices rather than the patch's welded ones."""
import numpy as np

from ..._shared.jit import B1, F2, callee, f8
from ...algebra.vec3 import _distance
from ..bvh import BVH_ARRAYS
from .locate import _meet, _plane_through
from .records import FROM_MISSES, OK


@callee((BVH_ARRAYS, B1, F2, f8, f8), cost=5.0)
def _guess(bvh, boundary, blades, snap, min_sine):
    """Where the blade meets the skin at both times, on the whole surface (``locate._meet``), the plane
    through the first point and the blade at t_(i+1), and the margin of ``region.py`` with the hit
    faces' edges, widened (``locate`` may snap the points a little further).

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
    no_list = np.zeros(0, np.int64)
    for i in range(2):
        kind, _, point, _, face = _meet(bvh, positions, faces, boundary, no_list, blades[2 * i], blades[2 * i + 1],
                                        snap)
        if kind < 0:
            return FROM_MISSES + i, np.zeros(4), 0.0, hit_faces
        points[i] = point
        hit_faces[i] = face
        if face >= 0:
            for c in range(3):
                longest = max(longest, _distance(positions[faces[face, c]], positions[faces[face, c - 1]]))
    plane = np.zeros(4)
    _plane_through(points[0], blades[2], blades[3], snap, min_sine, plane)
    return OK, plane, 1.25 * (_distance(points[0], points[1]) + longest) + 4.0 * snap, hit_faces
