"""Geometry kernels against clifford and numpy: planes (from a normal and distance, from points,
moved by a versor), point-plane distance, segment-plane meet, point-line distance, barycentric
coordinates (codegen/kernels_geometry.py; the plane from a normal and the distance are written in the kernel
language, codegen/kernels_language.py).
"""
from __future__ import annotations

import numpy as np
import pytest
from clifford import g3c
from hypothesis import assume, given, strategies as st

from cgaskin.generated import kernels as K
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import (PLANE_IDX, call, cl_vector, cl_versor, clifford_point_tol,
                                          coefficients, covers, e1, e2, e3, einf, eo,
                                          moderate_scale_versors, record, to_mv, versor_coefficients)
from tests.helpers.tolerances import EPS, TOL, rel_err

# ==== planes ===================================================================================================
@covers("plane_from_normal_distance")
@given(S.unit_axes(), S.log_uniform(1e-3, 1e3), st.one_of(st.just(0.0), S.finite(-1e4, 1e4)),
       st.tuples(S.finite(-10, 10), S.finite(-10, 10)))
def test_plane_from_normal_distance(n, length, d, tangent):
    got = call(K.plane_from_normal_distance, n * length, d)
    expected = np.r_[n, d / length]
    assert record("plane_from_normal_distance", rel_err(got, expected, max(1.0, abs(d) / length))) <= TOL.kernel
    # clifford: a point of {x : (length n) . x = d} is on the dual plane, up(p) . pi = 0
    plane = S.Plane(n, d / length)
    if abs(plane.distance) <= TOL.moderate:
        p = plane.point_on(tangent)
        dist = (g3c.up(cl_vector(p)) | to_mv(got, PLANE_IDX))[()]
        assert abs(dist) <= clifford_point_tol(np.abs(p).max()) * max(1.0, np.abs(p).max())


def _cross_normal(a, b, c):
    cross = np.cross(b - a, c - a)
    return cross / np.linalg.norm(cross), float(np.linalg.norm(cross))


@covers("plane_from_points")
@given(S.triangles())
def test_plane_from_points(tri):
    a, b, c = tri
    got = call(K.plane_from_points, a, b, c)
    n, _ = _cross_normal(a, b, c)
    mx = float(np.max(np.abs(tri)))
    err_n = rel_err(got[:3], n, 1.0)
    err_d = rel_err(got[3], n @ a, mx)
    record("plane_from_points", max(err_n, err_d))
    # computed relative to a, the normal is as well conditioned as the triangle:
    # cond = (longest edge)^2 / |(b-a) x (c-a)| <= 1 / quality, whatever the distance from the origin
    bound = TOL.kernel * _condition(a, b, c)
    assert err_n <= bound and err_d <= bound
    for p in tri:                                       # the corners are on the plane
        assert abs(call(K.point_plane_distance, got, p)) <= 2 * bound * mx


def _condition(a, b, c) -> float:
    return 1.0 / S.triangle_quality(a, b, c)


@given(S.triangles(TOL.moderate, min_size=1.0))
def test_plane_from_points_vs_clifford(tri):
    a, b, c = tri
    got = call(K.plane_from_points, a, b, c)
    dual = ((g3c.up(cl_vector(a)) ^ g3c.up(cl_vector(b)) ^ g3c.up(cl_vector(c)) ^ einf) * (
        e1 ^ e2 ^ e3 ^ einf ^ eo).inv())(1)
    pc = coefficients(dual, PLANE_IDX, "dual plane")
    pc = pc / np.linalg.norm(pc[:3])
    n, cross = _cross_normal(a, b, c)
    mx = float(np.max(np.abs(tri)))
    pc = pc if pc[:3] @ n > 0 else -pc                  # orientation: the kernel follows (b-a) x (c-a)
    # clifford's outer product of up-projected points carries ~EPS |x|^2 per factor: its own error
    bound = TOL.kernel * _condition(a, b, c) + clifford_point_tol(mx) * mx ** 2 / cross
    assert record("plane_from_points (clifford)", rel_err(got, pc, max(1.0, mx))) <= bound


# Regression: until eef6fc7 the generated code expanded (b-a) x (c-a) in absolute coordinates, and a
# unit triangle 1e4 from the origin got a normal wrong by ~2e-6 (a 1e-2 triangle: wrong altogether).
@pytest.mark.parametrize("size", [1.0, 1e-2, 1e-4])
def test_plane_from_points_far_from_origin_precision(size):
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(200):
        a = rng.uniform(-1e4, 1e4, 3)
        b, c = a + size * rng.uniform(-1, 1, 3), a + size * rng.uniform(-1, 1, 3)
        if S.triangle_quality(a, b, c) < 0.1:
            continue
        n, _ = _cross_normal(a, b, c)
        worst = max(worst, rel_err(call(K.plane_from_points, a, b, c)[:3], n, 1.0))
    assert worst <= TOL.kernel, f"normal error {worst:.3g} for triangles of size {size} at 1e4"


@covers("plane_transform")
@given(moderate_scale_versors, S.planes(TOL.moderate))
def test_plane_transform_vs_clifford(sim, plane):
    got = call(K.plane_transform, versor_coefficients(sim), plane.array)
    cv = cl_versor(sim)
    moved = coefficients((cv * to_mv(plane.array, PLANE_IDX) * ~cv)(1), PLANE_IDX, "moved plane")
    expected = moved / np.linalg.norm(moved[:3])
    mag = max(1.0, abs(expected[3]))
    assert record("plane_transform (clifford)", rel_err(got, expected, mag)) <= TOL.clifford * max(1.0, sim.magnitude)


@given(S.versors(), S.planes(), st.lists(st.tuples(S.finite(-1e3, 1e3), S.finite(-1e3, 1e3)), min_size=1,
                                        max_size=3))
def test_plane_transform_large(sim, plane, tangents):
    got = call(K.plane_transform, sim.versor(), plane.array)
    n_expected = sim.rotation_matrix() @ plane.normal              # orientation is kept
    d_expected = sim.scale * plane.distance + n_expected @ sim.translation
    mag = max(sim.magnitude, sim.scale * abs(plane.distance))
    err = max(rel_err(got[:3], n_expected, 1.0), rel_err(got[3], d_expected, mag))
    assert record("plane_transform", err) <= TOL.large
    for tangent in tangents:                            # moved points stay on the moved plane
        y = sim.apply(plane.point_on(tangent))
        scale = max(mag, float(np.abs(y).max()))
        assert abs(call(K.point_plane_distance, got, y)) <= TOL.large * scale


@covers("point_plane_distance")
@given(S.planes(), S.points())
def test_point_plane_distance(plane, x):
    got = float(K.point_plane_distance(plane.array, x))
    expected = float(plane.normal @ x - plane.distance)
    scale = max(1.0, float(np.abs(x).max()), abs(plane.distance))
    assert record("point_plane_distance", abs(got - expected) / scale) <= TOL.kernel


@given(S.planes(TOL.moderate), S.moderate_points())
def test_point_plane_distance_vs_clifford(plane, x):
    got = float(K.point_plane_distance(plane.array, x))
    expected = (g3c.up(cl_vector(x)) | to_mv(plane.array, PLANE_IDX))[()]
    assert abs(got - expected) <= clifford_point_tol(np.abs(x).max()) * max(1.0, np.abs(x).max())


@covers("segment_plane")
@given(S.planes(), S.points(), S.points())
def test_segment_plane(plane, a, b):
    da = float(plane.normal @ a - plane.distance)
    db = float(plane.normal @ b - plane.distance)
    assume(abs(da - db) > 1e-6 * max(1.0, np.abs(a).max(), np.abs(b).max()))
    got = call(K.segment_plane, plane.array, a, b)
    t = da / (da - db)
    scale = max(1.0, float(np.abs(a).max()), float(np.abs(b).max()), abs(plane.distance))
    # the signed distances carry ~EPS * scale each; t = da / (da - db) amplifies that by 1 / |da - db|
    t_bound = TOL.kernel * scale * (1.0 + 2.0 * abs(t)) / abs(da - db)
    assert record("segment_plane", abs(got[0] - t) / t_bound * TOL.kernel) <= TOL.kernel
    x_bound = TOL.kernel * scale * (1.0 + abs(t)) + t_bound * float(np.abs(b - a).max())
    assert float(np.max(np.abs(got[1:] - (a + t * (b - a))))) <= x_bound
    if 0.0 <= t <= 1.0:                                   # a crossing point is on the plane
        assert abs(call(K.point_plane_distance, plane.array, got[1:])) <= 10 * TOL.kernel * scale


def test_segment_plane_parallel_is_not_finite():
    plane = np.array([0.0, 0.0, 1.0, 1.0])
    t = call(K.segment_plane, plane, np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]))[0]
    assert not np.isfinite(t)                      # error_model='numpy': no exception, t = -inf


# ==== point-line distance ======================================================================================
def _line_distance(a, u, x) -> float:
    return float(np.linalg.norm(np.cross(x - a, u)) / np.linalg.norm(u))


def _offset_from_line(u, along, height, around):
    """along û + height n, n a unit vector perpendicular to u (its angle about u is ``around``)."""
    uh = u / np.linalg.norm(u)
    helper = np.eye(3)[int(np.argmin(np.abs(uh)))]
    n1 = np.cross(uh, helper)
    n1 /= np.linalg.norm(n1)
    n2 = np.cross(uh, n1)
    return along * uh + height * (np.cos(around) * n1 + np.sin(around) * n2)


_near_line_offsets = st.tuples(S.finite(-1e3, 1e3), st.one_of(st.just(0.0), S.log_uniform(1e-6, 1e3)),
                               S.finite(0.0, 6.3))


@covers("point_line_distance")
@given(S.points(), S.unit_axes(), S.log_uniform(1e-3, 1e3),
       st.one_of(S.points().map(lambda x: ("point", x)), _near_line_offsets.map(lambda o: ("offset", o))))
def test_point_line_distance(a, axis, length, where):
    u = axis * length
    kind, value = where
    x = value if kind == "point" else a + _offset_from_line(u, *value)
    got = K.point_line_distance(a, u, x)
    assert isinstance(got, float)                         # a Scalar comes back as a float
    expected = _line_distance(a, u, x)
    # both work with x − a (its rounding is the same in both): each coefficient of (x − a) ∧ u carries
    # ~EPS |x − a||u|, so below ~EPS |x − a| the distance is float64 noise whatever the formula
    floor = 8 * EPS * float(np.linalg.norm(x - a))
    assert record("point_line_distance", abs(got - expected) / max(expected, floor / TOL.kernel, 1e-300)) <= TOL.kernel


# An expanded form ((x_i − a_i) u_j multiplied out, as the kernel language would write it) cancels
# terms ~|a|²|u|²: at 1e6 from the origin a unit distance would come out wrong in the 4th digit.
@pytest.mark.parametrize("far", [1e4, 1e6])
def test_point_line_distance_far_from_origin_precision(far):
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(300):
        a = rng.uniform(-far, far, 3)
        u = rng.normal(size=3) * 10 ** rng.uniform(-2, 2)
        x = a + _offset_from_line(u, rng.uniform(-10, 10), 10 ** rng.uniform(-2, 1), rng.uniform(0, 6.3))
        worst = max(worst, rel_err(K.point_line_distance(a, u, x), _line_distance(a, u, x)))
    assert worst <= TOL.kernel, f"distance error {worst:.3g} for lines {far:g} from the origin"


@given(S.moderate_points(), S.unit_axes(), S.log_uniform(0.1, 10.0),
       st.one_of(S.moderate_points().map(lambda x: ("point", x)),
                 st.tuples(S.finite(-10, 10), st.one_of(st.just(0.0), S.log_uniform(1e-6, 10.0)),
                           S.finite(0.0, 6.3)).map(lambda o: ("offset", o))))
def test_point_line_distance_vs_clifford(a, axis, length, where):
    u = axis * length
    kind, value = where
    x = value if kind == "point" else a + _offset_from_line(u, *value)
    got = K.point_line_distance(a, u, x)
    # the conformal line through a along u, L = up(a) ∧ u ∧ e∞: d² = −(X ∧ L)² / L² for X = up(x)
    line = g3c.up(cl_vector(a)) ^ cl_vector(u) ^ einf
    meet = g3c.up(cl_vector(x)) ^ line
    d2 = -(meet * meet)[()] / (line * line)[()]
    mag = max(1.0, float(np.abs(a).max()), float(np.abs(x).max()))
    # clifford's up loses ~EPS |x|² (the oracle's own error, on d² ~ |x|²)
    assert record("point_line_distance (clifford)", abs(got * got - d2) / mag ** 2) <= clifford_point_tol(mag)


def test_point_line_distance_degenerate():
    a, x = np.array([1.0, 2.0, 3.0]), np.array([4.0, -5.0, 6.0])
    assert K.point_line_distance(a, np.array([0.0, 0.0, 2.0]), a) == 0.0             # x on the line
    assert np.isnan(K.point_line_distance(a, np.zeros(3), x))                        # no direction: NaN


@covers("barycentric")
@given(S.triangles(), st.tuples(S.finite(-1.0, 2.0), S.finite(-1.0, 2.0)), S.finite(-1.0, 1.0))
def test_barycentric(tri, lam, height):
    a, b, c = tri
    u, w = b - a, c - a
    n, cross = _cross_normal(a, b, c)
    size = float(max(np.linalg.norm(u), np.linalg.norm(w)))
    p = a + lam[0] * u + lam[1] * w + height * size * n
    got = call(K.barycentric, a, b, c, p)
    assert abs(got.sum() - 1.0) <= TOL.kernel * max(1.0, np.abs(got).max())
    expected, *_ = np.linalg.lstsq(np.column_stack([u, w]), p - a, rcond=None)
    # both sides work relative to a; the condition number of [u w] is bounded by the triangle quality
    cond = size ** 2 / cross
    err = rel_err(got[1:], expected, max(1.0, float(np.abs(expected).max())))
    assert record("barycentric", err) <= TOL.kernel * cond
    if height == 0.0:                                     # points of the plane are reconstructed
        rebuilt = got[0] * a + got[1] * b + got[2] * c
        assert rel_err(rebuilt, p, max(1.0, float(np.abs(tri).max()))) <= TOL.kernel * cond
