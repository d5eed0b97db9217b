"""An independent statement of the region a tear stroke may tear (runtime/surgery/tear/region.py):
the convex hull of the blade at both times, widened by |S_{i+1} - S_i| plus the longest edge of the two
faces the blade hit. Plain numpy: the nearest point of each hull triangle by least squares over the
triangle's barycentric coordinates, clipped by trying every edge and corner."""
from __future__ import annotations

import itertools

import numpy as np


def _segment_distance(p, a, b):
    d = b - a
    t = 0.0 if not d @ d else float(np.clip((p - a) @ d / (d @ d), 0.0, 1.0))
    return float(np.linalg.norm(a + t * d - p))


def _triangle_distance(p, a, b, c):
    edges = min(_segment_distance(p, *pair) for pair in ((a, b), (b, c), (c, a)))
    basis = np.stack([b - a, c - a], axis=1)                       # (3, 2)
    coef, *_ = np.linalg.lstsq(basis, p - a, rcond=None)
    if coef.min() >= 0 and coef.sum() <= 1:                        # the foot lies inside the face
        return min(edges, float(np.linalg.norm(a + basis @ coef - p)))
    return edges


def hull_distance(point, blades) -> float:
    """How far ``point`` (3,) lies outside the convex hull of the four points of ``blades`` (two (2, 3)
    blade positions); 0 inside."""
    q = np.asarray(blades, np.float64).reshape(4, 3)
    p = np.asarray(point, np.float64)
    # inside the tetrahedron: p is a convex combination of the four corners
    if abs(np.linalg.det(q[:3] - q[3])) > 1e-12 * np.ptp(q, axis=0).max() ** 3:
        lam = np.linalg.solve((q[:3] - q[3]).T, p - q[3])
        if lam.min() >= 0 and lam.sum() <= 1:
            return 0.0
    return min(_triangle_distance(p, *q[list(t)]) for t in itertools.combinations(range(4), 3))


def margin(points, faces, hit_faces, s_i, s_next) -> float:
    """|S_{i+1} - S_i| plus the longest edge of the hit faces."""
    corners = np.asarray(points)[np.asarray(faces)[np.asarray(hit_faces)]]
    longest = max(np.linalg.norm(corners[:, k] - corners[:, (k + 1) % 3], axis=1).max() for k in range(3))
    return float(np.linalg.norm(np.asarray(s_next) - np.asarray(s_i)) + longest)
