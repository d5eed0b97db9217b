"""Whether a point is inside a model: the generalised winding number of its surface (Jacobson et al.,
"Robust inside-outside segmentation using generalized winding numbers", 2013): the solid angle the
faces subtend at the point over 4π; 1 inside a closed, outward-facing surface, 0 outside, between for an
open one (above one half: mostly enclosed)."""
from __future__ import annotations

import math

from ..._shared.jit import F1, F2, I2, kernel


@kernel((F2, I2, F1), cost=0.2)
def winding_number(positions, faces, point):
    """The winding number at point (3,) of the surface positions (n, 3), faces (m, 3): the sum of the
    faces' signed solid angles (Van Oosterom and Strackee's formula) over 4π."""
    total = 0.0
    for f in range(faces.shape[0]):
        a = positions[faces[f, 0]] - point
        b = positions[faces[f, 1]] - point
        c = positions[faces[f, 2]] - point
        la, lb, lc = math.sqrt((a * a).sum()), math.sqrt((b * b).sum()), math.sqrt((c * c).sum())
        det = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
               + a[2] * (b[0] * c[1] - b[1] * c[0]))
        den = la * lb * lc + (a * b).sum() * lc + (b * c).sum() * la + (c * a).sum() * lb
        total += 2.0 * math.atan2(det, den)
    return total / (4.0 * math.pi)
