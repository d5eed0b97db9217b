"""The public versor API (cgaskin.versor): batching, algebraic laws, round trips and blending (its
errors: test_versor_errors.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, strategies as st

from tests.helpers import strategies as S
from cgaskin import versor as V
from tests.helpers.tolerances import TOL, matrix_scale, rel_err


def same_map(a, b, scale=None) -> float:
    """Relative difference of the affine maps of two versors (sign-free)."""
    ma, mb = V.to_matrix(a), V.to_matrix(b)
    return rel_err(ma, mb, scale)


def scale_of(v) -> float:
    return float(np.cbrt(np.linalg.det(V.to_affine(v)[..., :3])))


# ==== shapes and broadcasting ================================================================================
def test_constructor_shapes():
    assert V.identity().shape == (12,) and V.identity(3).shape == (3, 12) and V.identity((2, 3)).shape == (2, 3, 12)
    assert V.translator(np.zeros(3)).shape == (12,)
    assert V.translator(np.zeros((5, 3))).shape == (5, 12)
    assert V.translator(np.zeros((2, 4, 3))).shape == (2, 4, 12)
    assert V.translator(np.zeros((0, 3))).shape == (0, 12)
    assert V.rotor([0, 0, 1], 1.0).shape == (12,)
    assert V.rotor([0, 0, 1], np.zeros(5)).shape == (5, 12)
    assert V.rotor(np.ones((5, 3)), 0.3).shape == (5, 12)
    assert V.rotor(np.ones((2, 1, 3)), np.zeros(4)).shape == (2, 4, 12)
    assert V.rotor_from_quaternion(np.tile([0, 0, 0, 1.0], (5, 1))).shape == (5, 12)
    assert V.dilator(2.0).shape == (12,) and V.dilator(np.full((3, 2), 2.0)).shape == (3, 2, 12)
    assert V.motor().shape == (12,)
    np.testing.assert_array_equal(V.motor(), V.identity())


def test_operation_shapes():
    v5 = V.compose(V.translator(np.arange(15.0).reshape(5, 3)), V.rotor([1, 2, 3], np.linspace(0, 3, 5)))
    one = V.dilator(1.5)
    assert V.compose(one, v5).shape == (5, 12) and V.compose(v5, one).shape == (5, 12)
    assert V.compose(v5[:, None], v5[None, :]).shape == (5, 5, 12)
    assert V.compose(one, one, one).shape == (12,)
    assert V.reverse(v5).shape == V.inverse(v5).shape == V.normalise(v5).shape == (5, 12)
    assert V.apply(one, np.zeros((7, 3))).shape == (7, 3)
    assert V.apply(v5, np.zeros((5, 3))).shape == (5, 3)
    assert V.apply(v5[:, None], np.zeros((7, 3))).shape == (5, 7, 3)
    assert V.apply(v5, np.zeros(3)).shape == (5, 3)
    assert V.to_affine(v5).shape == (5, 3, 4) and V.to_affine(one).shape == (3, 4)
    assert V.to_matrix(v5).shape == (5, 4, 4) and V.to_matrix(one).shape == (4, 4)
    assert V.from_matrix(V.to_matrix(v5)).shape == (5, 12)
    assert V.log(v5).shape == (5, 7) and V.exp(V.log(v5)).shape == (5, 12)
    pairs = np.stack([v5, v5[::-1]], axis=1)                                   # (5, 2, 12)
    w = np.tile([0.25, 0.75], (5, 1))
    assert V.blend_linear(pairs, w).shape == (5, 12) and V.blend_log(pairs, w).shape == (5, 12)
    assert V.is_versor(v5).shape == (5,) and V.is_versor(one).shape == ()
    assert V.apply(v5[:0], np.zeros((0, 3))).shape == (0, 3)


@given(st.lists(S.versors(), min_size=1, max_size=4), st.lists(S.points(), min_size=1, max_size=4))
def test_batches_equal_rows(sims, pts):
    vs = np.stack([s.versor() for s in sims])
    x = np.stack(pts)
    out = V.apply(vs[:, None], x[None, :])                                  # (n, m, 3)
    for i, v in enumerate(vs):
        for j, p in enumerate(x):
            np.testing.assert_array_equal(out[i, j], V.apply(v, p))
    np.testing.assert_array_equal(V.to_matrix(vs)[-1], V.to_matrix(vs[-1]))
    np.testing.assert_array_equal(V.compose(vs, vs[::-1])[0], V.compose(vs[0], vs[-1]))


def test_non_contiguous_and_float32_inputs():
    rng = np.random.default_rng(5)
    vs = V.compose(V.translator(rng.uniform(-5, 5, (6, 3))), V.rotor(rng.normal(size=(6, 3)), rng.uniform(-3, 3, 6)))
    x = rng.uniform(-5, 5, (6, 3))
    expected = V.apply(vs[::2], x[::2])
    np.testing.assert_array_equal(V.apply(np.asfortranarray(vs)[::2], np.asfortranarray(x)[::2]), expected)
    np.testing.assert_array_equal(V.apply(vs.T.copy().T[::2], x.T.copy().T[::2]), expected)
    x32 = x.astype(np.float32)
    np.testing.assert_array_equal(V.apply(vs, x32), V.apply(vs, x32.astype(np.float64)))
    np.testing.assert_array_equal(V.translator([1, 2, 3]), V.translator(np.array([1.0, 2.0, 3.0])))


# ==== algebraic laws ===========================================================================================
@given(S.versors(), S.versors(), S.versors())
def test_compose_is_associative_and_matches_matrices(a, b, c):
    va, vb, vc = a.versor(), b.versor(), c.versor()
    left = V.compose(V.compose(va, vb), vc)
    right = V.compose(va, V.compose(vb, vc))
    both = V.compose(va, vb, vc)
    ma, mb, mc = a.matrix(), b.matrix(), c.matrix()
    scale = matrix_scale(ma, mb, mc)
    expected = ma @ mb @ mc
    # products reach scales 1e-6 .. 1e6, where the versor form itself loses ~EPS max(s, 1/s)
    tol = TOL.scale_bound(a.scale, b.scale, c.scale)
    for got in (left, right, both):
        assert rel_err(V.to_matrix(got), expected, scale) <= tol
    assert rel_err(V.to_matrix(left), V.to_matrix(right), scale) <= tol


@given(S.versors(), S.points())
def test_compose_applies_right_factor_first(sim, x):
    t = V.translator([1.0, 0.0, 0.0])
    v = sim.versor()
    mag = max(sim.magnitude, sim.scale * float(np.abs(x).max()), 1.0)
    assert rel_err(V.apply(V.compose(t, v), x), sim.apply(x) + [1.0, 0, 0], mag) <= TOL.large
    assert rel_err(V.apply(V.compose(v, t), x), sim.apply(x + [1.0, 0, 0]), mag + sim.scale) <= TOL.large


@given(S.versors(), S.points())
def test_inverse(sim, x):
    v = sim.versor()
    inv = V.inverse(v)
    m, m_inv = sim.matrix(), np.linalg.inv(sim.matrix())
    assert rel_err(V.to_matrix(inv), m_inv, matrix_scale(m_inv)) <= TOL.large
    assert rel_err(V.to_matrix(V.compose(v, inv)), np.eye(4), matrix_scale(m, m_inv)) <= TOL.large
    assert rel_err(V.to_matrix(V.compose(inv, v)), np.eye(4), matrix_scale(m_inv, m)) <= TOL.large
    assert rel_err(V.inverse(inv), v) <= TOL.large
    y = V.apply(v, x)
    mag = max(1.0, float(np.abs(x).max()), float(np.abs(y).max()) / sim.scale, sim.magnitude / sim.scale)
    assert rel_err(V.apply(inv, y), x, mag) <= TOL.large


@given(S.versors())
def test_reverse_is_inverse_of_unit_versors(sim):
    v = sim.versor()
    assert rel_err(V.reverse(v), V.inverse(v)) <= TOL.large


# ==== matrices =================================================================================================
@given(S.versors())
def test_from_matrix_to_matrix_round_trip(sim):
    m = sim.matrix()
    v = V.from_matrix(m)
    assert V.is_versor(v)
    assert rel_err(V.to_matrix(v), m, max(sim.magnitude, 1.0)) <= TOL.large
    back = V.from_matrix(V.to_matrix(sim.versor()))
    assert min(rel_err(back, sim.versor()), rel_err(back, -sim.versor())) <= TOL.large


@given(S.versors())
def test_from_matrix_float32_noise(sim):
    m = sim.matrix().astype(np.float32)
    v = V.from_matrix(m)
    assert V.is_versor(v)
    assert rel_err(V.to_matrix(v)[:3, :3], m[:3, :3], sim.scale) <= 1e-6
    assert rel_err(V.to_matrix(v)[:3, 3], m[:3, 3], sim.magnitude) <= 1e-6


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, -2, 3)])
def test_from_matrix_half_turn(axis):
    sim = S.Similarity(np.asarray(axis, float) / np.linalg.norm(axis), math.pi, np.array([1.0, 2, 3]), 2.0)
    v = V.from_matrix(sim.matrix())
    assert rel_err(V.to_matrix(v), sim.matrix(), sim.magnitude) <= TOL.large


def test_to_affine_is_matrix_top_rows():
    v = V.compose(V.translator([1, 2, 3]), V.rotor([0, 0, 1], math.pi / 2), V.dilator(2.0))
    np.testing.assert_allclose(V.to_affine(v), [[0, -2, 0, 1], [2, 0, 0, 2], [0, 0, 2, 3]], atol=1e-15)
    np.testing.assert_array_equal(V.to_matrix(v)[:3], V.to_affine(v))
    np.testing.assert_array_equal(V.to_matrix(v)[3], [0, 0, 0, 1])


# ==== blending ================================================================================================
def _pair(a, b):
    return np.stack([a, b])


@given(S.versors(), S.versors())
def test_blends_at_end_weights_return_inputs(s1, s2):
    a, b = s1.versor(), s2.versor()
    scale = max(s1.magnitude, s2.magnitude, 1.0)
    for blend in (V.blend_linear, V.blend_log):
        got_a = blend(_pair(a, b), [1.0, 0.0])
        got_b = blend(_pair(a, b), [0.0, 1.0])
        assert same_map(got_a, a, scale) <= TOL.large, blend.__name__
        assert same_map(got_b, b, scale) <= TOL.large, blend.__name__


@given(S.moderate_versors(), S.translations(TOL.moderate), st.floats(0.0, 1.0))
def test_blend_linear_translations_interpolate(sim, t2, w):
    """Same rotation and scale: the linear blend moves the translation along the segment."""
    other = S.Similarity(sim.axis, sim.angle, t2, sim.scale)
    got = V.blend_linear(_pair(sim.versor(), other.versor()), [1 - w, w])
    expected = S.Similarity(sim.axis, sim.angle, (1 - w) * sim.translation + w * t2, sim.scale)
    assert same_map(got, expected.versor(), max(sim.magnitude, 1.0)) <= TOL.large


@given(S.translations(), S.translations(), st.floats(0.0, 1.0))
def test_blend_log_translations_interpolate(t1, t2, w):
    got = V.blend_log(_pair(V.translator(t1), V.translator(t2)), [1 - w, w])
    mag = max(1.0, float(np.abs(t1).max()), float(np.abs(t2).max()))
    assert rel_err(V.to_affine(got)[:, 3], (1 - w) * t1 + w * t2, mag) <= TOL.large
    assert rel_err(V.to_affine(got)[:, :3], np.eye(3), 1.0) <= TOL.large


@given(S.unit_axes(), S.angles(-math.pi + 1e-3, math.pi - 1e-3), S.angles(-math.pi + 1e-3, math.pi - 1e-3),
       st.floats(0.0, 1.0))
def test_blend_rotations_about_one_axis_stay_between(axis, a1, a2, w):
    pair = _pair(V.rotor(axis, a1), V.rotor(axis, a2))
    # linear blending (nlerp): the rotors are sign-aligned first, so the blend takes the short arc
    # from a1 to a2 (or to a2 -+ 2 pi when |a1 - a2| > pi) and its angle stays on that arc
    b2 = a2 if abs(a1 - a2) <= math.pi else a2 - math.copysign(2 * math.pi, a2 - a1)
    lin = V.blend_linear(pair, [1 - w, w])
    half = math.atan2((1 - w) * math.sin(a1 / 2) + w * math.sin(b2 / 2),
                      (1 - w) * math.cos(a1 / 2) + w * math.cos(b2 / 2))
    assert min(a1, b2) - 1e-12 <= 2 * half <= max(a1, b2) + 1e-12
    assert same_map(lin, V.rotor(axis, 2 * half), 1.0) <= TOL.large
    # log blending relative to the first rotor: the angle moves linearly along the same short arc
    got = V.blend_log(pair, [1 - w, w])
    expected = V.rotor(axis, (1 - w) * a1 + w * b2)
    assert same_map(got, expected, 1.0) <= TOL.large


@given(S.unit_axes(), S.angles(), S.translations(10.0), S.unit_axes(), S.angles(), S.translations(10.0),
       st.floats(0.0, 1.0))
def test_blend_log_of_two_motors_is_the_screw_motion(axis0, a0, t0, axis1, a1, t1, w):
    """Oracle: the rigid motion M0 (M0^-1 M1)^w, the principal matrix power (scipy), i.e. the screw
    motion from M0 to M1 along the shorter way round."""
    from scipy.linalg import expm, logm
    m0 = V.to_matrix(V.motor(axis0, a0, t0))
    m1 = V.to_matrix(V.motor(axis1, a1, t1))
    relative = np.linalg.solve(m0, m1)
    angle = math.acos(np.clip((np.trace(relative[:3, :3]) - 1) / 2, -1, 1))
    assume(angle < math.pi - 1e-3)          # at a half turn both ways round are as short
    expected = m0 @ expm(w * np.real(logm(relative)))
    got = V.to_matrix(V.blend_log(_pair(V.motor(axis0, a0, t0), V.motor(axis1, a1, t1)), [1 - w, w]))
    assert np.abs(got - expected).max() <= 1e-8 * max(1.0, np.abs(t0).max(), np.abs(t1).max())


@given(S.versors(), S.versors(), st.floats(0.0, 1.0))
def test_blended_scale_is_between(s1, s2, w):
    pair = _pair(s1.versor(), s2.versor())
    lo, hi = min(s1.scale, s2.scale), max(s1.scale, s2.scale)
    lin = scale_of(V.blend_linear(pair, [1 - w, w]))
    assert lo * (1 - 1e-12) <= lin <= hi * (1 + 1e-12)
    log_blend = scale_of(V.blend_log(pair, [1 - w, w]))
    expected = math.exp((1 - w) * math.log(s1.scale) + w * math.log(s2.scale))   # geometric interpolation
    assert abs(log_blend - expected) <= 1e-11 * expected


@given(S.versors(), st.floats(0.0, 1.0))
def test_antipodal_versors_blend_to_the_same_map(sim, w):
    """V and -V are the same transformation: blending them must not cancel."""
    v = sim.versor()
    scale = max(sim.magnitude, 1.0)
    assert same_map(V.blend_linear(_pair(v, -v), [1 - w, w]), v, scale) <= TOL.large
    assert same_map(V.blend_log(_pair(v, -v), [1 - w, w]), v, scale) <= TOL.large


@given(S.versors(), S.versors(), st.floats(0.0, 1.0))
def test_blend_ignores_input_signs(s1, s2, w):
    a, b = s1.versor(), s2.versor()
    scale = max(s1.magnitude, s2.magnitude, 1.0)
    for blend in (V.blend_linear, V.blend_log):
        ref = blend(_pair(a, b), [1 - w, w])
        assert same_map(blend(_pair(a, -b), [1 - w, w]), ref, scale) <= TOL.large
        assert same_map(blend(_pair(-a, b), [1 - w, w]), ref, scale) <= TOL.large
