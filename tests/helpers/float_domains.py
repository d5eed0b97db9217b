"""Inputs where a float32 kernel can be compared with the float64 numba kernel at 1e-5: what each kernel
input means, drawn by hypothesis (the WGSL and the C float tests in tests/targets).

Raw coordinates in [-10, 10] (``target_cases.input_arrays``) make sense for points and affine maps,
but not for a versor, a plane, a rotation matrix or a triangle: random coefficients there give
ill-conditioned results (a near-zero versor norm, a near-degenerate triangle, a segment parallel to
its plane) where float64 itself loses digits and f32 cannot be compared at 1e-5. So:

- 12-blade multivector (Versor): w · T(t) R(axis, angle) D(s), built with the numba kernels
  versor_translator, versor_rotor, versor_dilator, gp_versor_versor; t in [-10, 10]^3, the axis a unit
  vector, angle in [-3, 3] (versor_log is ill-conditioned at angle π: 1/sin(θ/2) of the motor part),
  s in [0.5, 2] log-uniform, a weight w in [0.5, 2] (versors need not be unit).
- 8-blade multivector (Motor): T(t) R(axis, angle).
- 4-blade multivector (Plane): plane_from_normal_distance(unit normal, d in [-10, 10]).
- built-in kernels' arrays and scalars, by meaning: a rotation axis or plane normal of length
  [0.1, 10]; a quaternion in [-1, 1]^4 with |q| >= 0.1 (w += 1 where it is shorter); a scale in
  [0.01, 100] log-uniform; the matrix of versor_from_matrix a 4x4 similarity (versor_to_affine of a
  versor); the L of versor_exp a versor_log; triangles (plane_from_points, barycentric) with sides
  in [0.1, 10] and angles of at least 0.3 rad; segments (segment_plane) of length [1, 10] at least
  0.2 rad off their plane, meeting it at t in [-1, 2]; the direction u of point_line_distance a vector
  of length [0.1, 10] (u = 0 has no line: NaN).
- anything else (points, affine maps, a user's arrays and scalars): [-10, 10].
"""
from __future__ import annotations

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tests.helpers.target_cases import builtin_kernels

#: rows of every drawn array that hypothesis draws element by element (the rest: numpy, seeded by it)
HYPOTHESIS_ROWS = 2


def _uniform(src, rows, width, lo, hi):
    """(rows, width) (or (rows,) for width None) float64 in [lo, hi]: the first ``HYPOTHESIS_ROWS``
    rows drawn element by element by hypothesis (its bounds, zeros, repeated values, shrinking), the
    others by a numpy generator seeded by hypothesis (drawing every element through hypothesis
    costs ~0.1 s per example for 64 rows of versors)."""
    draw, rng = src
    shape = (rows,) if width is None else (rows, width)
    head = min(rows, HYPOTHESIS_ROWS)
    elements = st.floats(lo, hi, allow_nan=False, width=64)
    drawn = draw(hnp.arrays(np.float64, (head, *shape[1:]), elements=elements))
    return np.concatenate([drawn, rng.uniform(lo, hi, (rows - head, *shape[1:]))])


def _batch(name, *args, width):
    """The numba batch kernel ``name`` of the built-in catalogue on ``args``: (rows, width)."""
    _, module = builtin_kernels()
    out = np.empty((len(args[0]), width))
    getattr(module, f"{name}_batch")(*(np.ascontiguousarray(a, np.float64) for a in args), out)
    return out


def _unit(src, rows):
    """(rows, 3) unit vectors from spherical coordinates (never degenerate)."""
    phi = _uniform(src, rows, None, 0.0, 2 * np.pi)
    z = _uniform(src, rows, None, -1.0, 1.0)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _log_uniform(src, rows, lo, hi):
    return np.exp(_uniform(src, rows, None, np.log(lo), np.log(hi)))


def _motor(src, rows):
    """(rows, 12) T(t) R(axis, angle) (its e∞0 blades are zero)."""
    rotor = _batch("versor_rotor", _unit(src, rows), _uniform(src, rows, None, -3.0, 3.0), width=12)
    translator = _batch("versor_translator", _uniform(src, rows, 3, -10.0, 10.0), width=12)
    return _batch("gp_versor_versor", translator, rotor, width=12)


def _versor(src, rows):
    """(rows, 12) w T R D (see the module docstring)."""
    dilator = _batch("versor_dilator", _log_uniform(src, rows, 0.5, 2.0), width=12)
    weight = _uniform(src, rows, None, 0.5, 2.0)[:, None]
    return weight * _batch("gp_versor_versor", _motor(src, rows), dilator, width=12)


def _plane(src, rows):
    return _batch("plane_from_normal_distance", _unit(src, rows), _uniform(src, rows, None, -10.0, 10.0),
                  width=4)


def _rotation(src, rows):
    """(rows, 3, 3) rotation matrices (versor_to_affine of rotors)."""
    rotor = _batch("versor_rotor", _unit(src, rows), _uniform(src, rows, None, -np.pi, np.pi), width=12)
    return _batch("versor_to_affine", rotor, width=12).reshape(rows, 3, 4)[:, :, :3]


def _triangle(src, rows):
    """a, b, c (rows, 3) each: sides from a in [0.1, 10], angle at a in [0.3, π − 0.3]."""
    a = _uniform(src, rows, 3, -10.0, 10.0)
    l1, l2 = _log_uniform(src, rows, 0.1, 10.0), _log_uniform(src, rows, 0.1, 10.0)
    phi = _uniform(src, rows, None, 0.3, np.pi - 0.3)
    local_b = np.stack([l1, 0 * l1, 0 * l1], axis=1)
    local_c = np.stack([l2 * np.cos(phi), l2 * np.sin(phi), 0 * l2], axis=1)
    rot = _rotation(src, rows)
    return a, a + np.einsum("rij,rj->ri", rot, local_b), a + np.einsum("rij,rj->ri", rot, local_c)


def _segment(src, rows, plane):
    """a, b (rows, 3): a segment of length [1, 10], at least 0.2 rad off the plane (|cos| to the
    normal >= sin 0.2), that meets the plane at t in [-1, 2]. (t = d_a / (d_a − d_b) is conditioned
    by |x| / (length · cos): at |x| = 10 a segment of length 0.1 leaves f32 only 1e-4 of t.)"""
    n, d = plane[:, :3], plane[:, 3]
    x = _uniform(src, rows, 3, -10.0, 10.0)
    on_plane = x - (np.einsum("ri,ri->r", x, n) - d)[:, None] * n
    u = _unit(src, rows)
    perp = u - np.einsum("ri,ri->r", u, n)[:, None] * n
    length = np.linalg.norm(perp, axis=1, keepdims=True)
    # u along n: any vector orthogonal to n will do
    fallback = np.cross(n, np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    fallback /= np.linalg.norm(fallback, axis=1, keepdims=True)
    perp = np.where(length > 1e-3, perp / np.maximum(length, 1e-3), fallback)
    cos = _uniform(src, rows, None, np.sin(0.2), 1.0) * np.where(_uniform(src, rows, None, 0, 1) < 0.5, -1, 1)
    step = _log_uniform(src, rows, 1.0, 10.0)[:, None] * (cos[:, None] * n + np.sqrt(1.0 - cos * cos)[:, None]
                                                           * perp)
    a = on_plane - _uniform(src, rows, None, -1.0, 2.0)[:, None] * step
    return a, a + step


def _axis(src, rows):
    return _unit(src, rows) * _log_uniform(src, rows, 0.1, 10.0)[:, None]


def _by_meaning(src, kernel, rows):
    """{input name: array} for built-in inputs that are not raw coordinates, else {}."""
    name = kernel.name
    if name == "versor_rotor":
        return {"axis": _axis(src, rows), "angle": _uniform(src, rows, None, -np.pi, np.pi)}
    if name == "versor_rotor_quaternion":
        q = _uniform(src, rows, 4, -1.0, 1.0)
        q[:, 3] += np.where(np.linalg.norm(q, axis=1) < 0.1, 1.0, 0.0)
        return {"q": q}
    if name == "versor_dilator":
        return {"scale": _log_uniform(src, rows, 0.01, 100.0)}
    if name == "versor_from_matrix":
        m = np.zeros((rows, 4, 4))
        m[:, :3, :] = _batch("versor_to_affine", _versor(src, rows), width=12).reshape(rows, 3, 4)
        m[:, 3, 3] = 1.0
        return {"m": m.reshape(rows, 16)}
    if name == "versor_exp":
        return {"L": _batch("versor_log", _versor(src, rows), width=7)}
    if name == "plane_from_normal_distance":
        return {"n": _axis(src, rows), "d": _uniform(src, rows, None, -10.0, 10.0)}
    if name in ("plane_from_points", "barycentric"):
        return dict(zip("abc", _triangle(src, rows)))
    if name == "point_line_distance":
        return {"u": _axis(src, rows)}
    if name == "segment_plane":
        plane = _plane(src, rows)
        return dict(zip(("plane", "a", "b"), (plane, *_segment(src, rows, plane))))
    return {}


#: {blade labels: drawing function} of the multivector types with a meaningful domain
MULTIVECTORS = {
    ("s", "e12", "e13", "e23", "e1i", "e2i", "e3i", "e123i", "eio", "e12io", "e13io", "e23io"): _versor,
    ("s", "e12", "e13", "e23", "e1i", "e2i", "e3i", "e123i"): _motor,
    ("e1", "e2", "e3", "ei"): _plane}


def kernel_inputs(kernel, rows: int):
    """A hypothesis strategy of ``kernel``'s inputs (one float64 array per input, (rows, size) or
    (rows,)) in the domains of the module docstring."""
    @st.composite
    def draw_inputs(draw):
        src = (draw, np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1))))
        known = _by_meaning(src, kernel, rows)
        arrays = []
        for inp in kernel.inputs:
            size = len(inp.symbols)
            if inp.name in known:
                arrays.append(known[inp.name])
            elif inp.kind == "multivector" and tuple(inp.labels) in MULTIVECTORS:
                arrays.append(MULTIVECTORS[tuple(inp.labels)](src, rows)[:, :size])
            else:
                arrays.append(_uniform(src, rows, None if inp.kind == "scalar" else size, -10.0, 10.0))
        return arrays
    return draw_inputs()
