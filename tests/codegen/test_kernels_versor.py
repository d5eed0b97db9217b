"""Versor kernels against clifford and float64 matrices: constructors (translator, rotor, dilator,
from_matrix), products (gp, reverse, inverse, residual) and normalise (codegen/kernels_versor.py; the
translator and the products are written in the kernel language, codegen/kernels_language.py).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, example, given, strategies as st

from cgaskin.generated import kernels as K
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import (MOTOR_IDX, ONE, VERSOR_IDX, call, cl_apply, cl_dilator, cl_rotor,
                                          cl_translator, cl_versor, clifford_point_tol, coefficients, covers,
                                          moderate_scale_versors, moderate_versors, null_coefficients,
                                          record, rel_err_sign, to_mv, versor_coefficients)
from tests.helpers.tolerances import TOL, rel_err

# ==== construction ===========================================================================================
@covers("versor_translator")
@given(S.translations())
def test_versor_translator(t):
    got = call(K.versor_translator, t)
    err = record("versor_translator", rel_err(to_mv(got).value, cl_translator(t).value, max(1.0, np.abs(t).max())))
    assert err <= TOL.kernel


@covers("versor_rotor")
@given(S.unit_axes(), S.angles(), S.log_uniform(1e-3, 1e3))
@example(np.array([0.0, 0.0, 1.0]), math.pi / 2, 1.0)
def test_versor_rotor(axis, angle, length):
    got = call(K.versor_rotor, axis * length, angle)
    err = record("versor_rotor", rel_err(to_mv(got).value, cl_rotor(axis, angle).value, 1.0))
    assert err <= TOL.kernel


def test_versor_rotor_right_handed():
    r = call(K.versor_rotor, np.array([0.0, 0.0, 1.0]), math.pi / 2)
    np.testing.assert_allclose(cl_apply(to_mv(r), [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(call(K.sandwich_versor_point, r, np.array([1.0, 0.0, 0.0])), [0, 1, 0], atol=1e-15)


@covers("versor_rotor_quaternion")
@given(S.unit_axes(), S.angles(), S.log_uniform(1e-3, 1e3))
def test_versor_rotor_quaternion(axis, angle, length):
    q = length * np.r_[math.sin(angle / 2) * axis, math.cos(angle / 2)]     # (x, y, z, w)
    got = call(K.versor_rotor_quaternion, q)
    err = record("versor_rotor_quaternion", rel_err(to_mv(got).value, cl_rotor(axis, angle).value, 1.0))
    assert err <= TOL.kernel


@covers("versor_dilator")
@given(S.scales(), S.moderate_points())
def test_versor_dilator(scale, x):
    got = call(K.versor_dilator, scale)
    expected = cl_dilator(scale)
    err = record("versor_dilator", rel_err(to_mv(got).value, expected.value))
    assert err <= TOL.kernel
    if np.any(x != 0):                                             # apply(D, x) == s x
        y = cl_apply(to_mv(got), x)
        mag = scale * float(np.abs(x).max())
        assert rel_err(y, scale * x, mag) <= clifford_point_tol(max(1.0, mag))


@covers("versor_from_matrix")
@given(moderate_scale_versors)
def test_versor_from_matrix_vs_clifford(sim):
    got = call(K.versor_from_matrix, sim.matrix().ravel())
    expected = versor_coefficients(sim)
    err = record("versor_from_matrix", rel_err_sign(got, expected))
    assert err <= TOL.kernel


@given(S.versors())
def test_versor_from_matrix_large(sim):
    m = sim.matrix()
    got = call(K.versor_from_matrix, m.ravel())
    a = call(K.versor_to_affine, got).reshape(3, 4)
    err_lin = rel_err(a[:, :3], m[:3, :3], sim.scale)
    err_t = rel_err(a[:, 3], m[:3, 3], sim.magnitude)
    record("versor_from_matrix", max(err_lin, err_t))
    assert err_lin <= TOL.large and err_t <= TOL.large
    residual, norm = K.versor_residual(got)
    assert norm > 0


@given(S.versors())
def test_versor_from_matrix_float32_noise(sim):
    """Matrices read from files carry float32 noise: the result must still be a true versor whose
    matrix is as close to the input as the input is to a similarity."""
    m = sim.matrix().astype(np.float32).astype(np.float64)
    got = call(K.versor_from_matrix, m.ravel())
    residual, norm = K.versor_residual(got)
    assert norm > 0 and residual <= TOL.kernel * float(np.sum(got * got))
    lin = m[:3, :3]
    defect = float(np.max(np.abs(lin.T @ lin / sim.scale ** 2 - np.eye(3))))
    a = call(K.versor_to_affine, got).reshape(3, 4)
    err_lin = rel_err(a[:, :3], lin, sim.scale)
    assert err_lin <= TOL.from_matrix_noise_factor * defect + TOL.large
    assert rel_err(a[:, 3], m[:3, 3], sim.magnitude) <= TOL.large


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -2, 3), (0, 1, -1e-9),
                                  (-1, -1, -1)])
@pytest.mark.parametrize("angle", [math.pi, -math.pi, math.pi * (1 - 1e-9), math.pi * (1 - 1e-6), 0.0, 1e-9])
@pytest.mark.parametrize("scale", [1.0, 0.01, 100.0])
def test_versor_from_matrix_half_turns(axis, angle, scale):
    sim = S.Similarity(np.asarray(axis, float) / np.linalg.norm(axis), angle, np.array([3.0, -1.0, 2.0]), scale)
    got = call(K.versor_from_matrix, sim.matrix().ravel())
    err = record("versor_from_matrix", rel_err_sign(got, versor_coefficients(sim)))
    assert err <= TOL.kernel
    for noisy in (sim.matrix().astype(np.float32).astype(np.float64),):
        v = call(K.versor_from_matrix, noisy.ravel())
        assert np.all(np.isfinite(v))
        a = call(K.versor_to_affine, v).reshape(3, 4)
        assert rel_err(a[:, :3], noisy[:3, :3], scale) <= 1e-6


# ==== products =================================================================================================
def _product_scale(a, b):
    return max(1.0, float(np.sum(np.abs(a)) * np.sum(np.abs(b))))


@covers("gp_motor_motor")
@given(S.coefficient_arrays(8), S.coefficient_arrays(8))
def test_gp_motor_motor_coefficients(a, b):
    got = call(K.gp_motor_motor, a, b)
    expected = coefficients(to_mv(a, MOTOR_IDX) * to_mv(b, MOTOR_IDX), MOTOR_IDX, "motor x motor")
    err = record("gp_motor_motor", rel_err(got, expected, _product_scale(a, b)))
    assert err <= TOL.kernel


@given(S.motors(TOL.moderate), S.motors(TOL.moderate))
def test_gp_motor_motor_of_motors(m1, m2):
    a, b = versor_coefficients(m1)[:8], versor_coefficients(m2)[:8]
    got = call(K.gp_motor_motor, a, b)
    expected = coefficients(cl_versor(m1) * cl_versor(m2), MOTOR_IDX, "motor x motor")
    assert record("gp_motor_motor", rel_err(got, expected, _product_scale(a, b))) <= TOL.kernel


@covers("gp_versor_versor")
@given(S.coefficient_arrays(12), S.coefficient_arrays(12))
def test_gp_versor_versor_coefficients(a, b):
    got = call(K.gp_versor_versor, a, b)
    expected = coefficients(to_mv(a) * to_mv(b), VERSOR_IDX, "versor x versor")
    err = record("gp_versor_versor", rel_err(got, expected, _product_scale(a, b)))
    assert err <= TOL.kernel


@given(moderate_versors, moderate_versors, S.moderate_points())
def test_gp_versor_versor_composes(s1, s2, x):
    """The product applies the right factor first (like matrices)."""
    a, b = versor_coefficients(s1), versor_coefficients(s2)
    ab = call(K.gp_versor_versor, a, b)
    assert record("gp_versor_versor", rel_err(ab, coefficients(cl_versor(s1) * cl_versor(s2)),
                                             _product_scale(a, b))) <= TOL.kernel
    expected = s1.apply(s2.apply(x))
    # the kernels' rounding scales with the versor's magnitude max(s, |t|) (design.md 3.4: ~EPS s)
    mag = max(1.0, float(np.abs(expected).max()), s1.scale * s2.scale * max(1.0, float(np.abs(x).max())))
    # a product's scale s1 s2 reaches 1e4, where the versor form loses ~EPS s (tolerances.py)
    assert rel_err(call(K.sandwich_versor_point, ab, x), expected, mag) <= TOL.scale_bound(s1.scale, s2.scale)


@covers("reverse_versor")
@given(S.coefficient_arrays(12))
def test_reverse_versor(v):
    got = call(K.reverse_versor, v)
    expected = coefficients(~to_mv(v), what="reverse")
    assert record("reverse_versor", rel_err(got, expected, max(1.0, np.abs(v).max()))) <= TOL.kernel


@covers("inverse_versor")
@given(moderate_scale_versors)
def test_inverse_versor_vs_clifford(sim):
    v = versor_coefficients(sim)
    got = call(K.inverse_versor, v)
    cv = cl_versor(sim)
    expected = coefficients(cv.inv(), what="inverse")
    assert record("inverse_versor", rel_err(got, expected)) <= TOL.kernel
    unit = to_mv(got) * cv
    assert rel_err(unit.value, ONE.value, max(1.0, np.abs(v).max() * np.abs(got).max())) <= TOL.kernel


@given(S.versors())
def test_inverse_versor_large(sim):
    got = call(K.inverse_versor, sim.versor())
    a = call(K.versor_to_affine, got).reshape(3, 4)
    m_inv = np.linalg.inv(sim.matrix())
    mag = max(1.0 / sim.scale, float(np.abs(m_inv[:3, 3]).max()))
    err = max(rel_err(a[:, :3], m_inv[:3, :3], 1.0 / sim.scale), rel_err(a[:, 3], m_inv[:3, 3], mag))
    assert record("inverse_versor", err) <= TOL.large


def _clifford_residual(v):
    """(max |non-scalar null-basis coefficient of V V~|, <V V~>_0) computed by clifford."""
    c = null_coefficients(to_mv(v) * ~to_mv(v))
    return float(np.max(np.abs(c[1:]))), float(c[0])


@covers("versor_residual")
@given(st.one_of(S.coefficient_arrays(12), S.non_versors()))
def test_versor_residual_vs_clifford(v):
    residual, norm = K.versor_residual(v)
    expected_residual, expected_norm = _clifford_residual(v)
    scale = max(1.0, float(np.sum(v * v)))
    err = max(abs(residual - expected_residual), abs(norm - expected_norm)) / scale
    assert record("versor_residual", err) <= TOL.kernel


@given(moderate_scale_versors)
def test_versor_residual_of_versors(sim):
    v = versor_coefficients(sim)
    residual, norm = K.versor_residual(v)
    assert abs(norm - 1.0) <= TOL.kernel * np.sum(v * v)       # T R D is normalised: <V V~>_0 = 1
    assert record("versor_residual", residual / np.sum(v * v)) <= TOL.kernel


# ==== normalise ================================================================================================
@covers("versor_normalise")
@given(S.versors(), st.one_of(S.log_uniform(1e-3, 1e3), S.log_uniform(1e-3, 1e3).map(lambda x: -x)))
def test_versor_normalise_exact_on_versors(sim, factor):
    v = sim.versor()
    got = call(K.versor_normalise, factor * v)
    expected = math.copysign(1.0, factor) * v
    assert record("versor_normalise", rel_err(got, expected)) <= TOL.kernel


def _align(a, b):
    """b with the sign that makes its rotor part agree with a's (V and -V are the same map)."""
    return b if np.dot(a[:4], b[:4]) >= 0 else -b


@given(moderate_versors, S.translations(TOL.moderate), S.weights(2))
def test_versor_normalise_translation_blend(sim, t2, w):
    """Sum w_i T(t_i) R D = T(sum w_i t_i) R D when the weights sum to 1."""
    other = S.Similarity(sim.axis, sim.angle, t2, sim.scale)
    blend = w[0] * versor_coefficients(sim) + w[1] * versor_coefficients(other)
    expected = versor_coefficients(S.Similarity(sim.axis, sim.angle, w[0] * sim.translation + w[1] * t2, sim.scale))
    assert record("versor_normalise", rel_err(call(K.versor_normalise, blend), expected)) <= TOL.kernel


@given(moderate_versors, S.unit_axes(), S.angles(), S.weights(2))
def test_versor_normalise_rotation_blend(sim, axis2, angle2, w):
    """Sum w_i T R_i D = T (sum w_i R_i) D: the rotor is the normalised blend of the rotors."""
    r1 = coefficients(cl_rotor(sim.axis, sim.angle))
    r2 = _align(r1, coefficients(cl_rotor(axis2, angle2)))
    rb = w[0] * r1 + w[1] * r2
    assume(np.linalg.norm(rb[:4]) > 1e-3)
    t, d = cl_translator(sim.translation), cl_dilator(sim.scale)
    blend = coefficients(t * to_mv(rb) * d)
    expected = coefficients(t * to_mv(rb / np.linalg.norm(rb[:4])) * d)
    err = rel_err(call(K.versor_normalise, blend), expected)
    assert record("versor_normalise", err) <= TOL.kernel


@given(moderate_versors, S.scales(), S.weights(2))
def test_versor_normalise_scale_blend(sim, scale2, w):
    """Sum w_i T R D_i: the dilator is (sum w ch_i) - (sum w sh_i) e-inf0, normalised:
    tanh(ln s / 2) = sum w sh_i / sum w ch_i."""
    ch = w[0] * math.cosh(math.log(sim.scale) / 2) + w[1] * math.cosh(math.log(scale2) / 2)
    sh = w[0] * math.sinh(math.log(sim.scale) / 2) + w[1] * math.sinh(math.log(scale2) / 2)
    s_blend = math.exp(2 * math.atanh(sh / ch))
    tr = cl_translator(sim.translation) * cl_rotor(sim.axis, sim.angle)
    blend = w[0] * coefficients(tr * cl_dilator(sim.scale)) + w[1] * coefficients(tr * cl_dilator(scale2))
    expected = coefficients(tr * cl_dilator(s_blend))
    assert record("versor_normalise", rel_err(call(K.versor_normalise, blend), expected)) <= TOL.kernel


@given(S.versors(), S.versors(), S.weights(2))
def test_versor_normalise_general_blend_is_versor(s1, s2, w):
    """Any convex blend of sign-aligned unit versors has a rotor part larger than its e-inf0 part (the
    rotor dot products are >= 0 and ch_i ch_j >= |sh_i sh_j|), and normalises to a unit versor."""
    a = s1.versor()
    b = _align(a, s2.versor())
    blend = w[0] * a + w[1] * b
    assert np.linalg.norm(blend[:4]) > np.linalg.norm(blend[8:])
    got = call(K.versor_normalise, blend)
    residual, norm = K.versor_residual(got)
    size = float(np.sum(got * got))
    assert abs(norm - 1.0) <= TOL.kernel * size and residual <= TOL.kernel * size
    if w[0] == 1.0:
        assert record("versor_normalise", rel_err(got, a)) <= TOL.kernel
