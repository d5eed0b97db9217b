"""The kernel catalogue: every CGA kernel the runtime calls, written as symbolic algebra.

Conventions (design.md §2): null basis e1, e2, e3, e∞, e0 with e0·e∞ = −1;
    translator  T(t) = 1 − ½ t e∞
    rotor       R = cos(θ/2) − sin(θ/2) (n₁e23 − n₂e13 + n₃e12)   (right-handed about unit axis n)
                  = w − x e23 + y e13 − z e12 for the unit quaternion (x, y, z, w)
    dilator     D(s) = cosh(ln s / 2) − sinh(ln s / 2) e∞0 = exp(−½ ln s e∞0), so D up(x) D̃ ∝ up(s x)
    versor      V = T R D, 12 blades; compose = geometric product (right factor applies first)
Points are Euclidean (3,) arrays: kernels up-project them and down-project results (dividing by the
e0 coefficient, which for the 12-blade type never depends on the point — the hoist pass checks it).
"""
from __future__ import annotations

from . import kernels_language as language
from .kernels_exp_log import versor_exp, versor_log
from .kernels_geometry import (barycentric, plane_from_points, plane_transform, point_line_distance,
                               segment_plane)
from .kernels_skinning import affine_point, sandwich_versor_point, versor_to_affine
from .kernels_versor import (versor_dilator, versor_from_matrix, versor_normalise, versor_residual, versor_rotor,
                             versor_rotor_quaternion)

# the kernels written in the kernel language, as catalogue entries like the builder ones
versor_translator, gp_motor_motor, gp_versor_versor, reverse_versor, inverse_versor, plane_from_normal_distance, \
    point_plane_distance = map(language.built, (
        language.versor_translator, language.gp_motor_motor, language.gp_versor_versor, language.reverse_versor,
        language.inverse_versor, language.plane_from_normal_distance, language.point_plane_distance))

#: every built-in kernel, as a function returning its Kernel IR, in the order of generated/kernels.py
KERNELS = (versor_translator, versor_rotor, versor_rotor_quaternion, versor_dilator, versor_from_matrix,
           gp_motor_motor, gp_versor_versor, reverse_versor, inverse_versor, versor_residual,
           versor_normalise, sandwich_versor_point, versor_to_affine, affine_point,
           plane_from_normal_distance, plane_from_points, plane_transform, point_plane_distance,
           segment_plane, point_line_distance, barycentric, versor_log, versor_exp)
