"""The versor logarithm and exponential against a float64 screw oracle and clifford's Taylor series,
round trips both ways, and the small-angle series (codegen/kernels_exp_log.py).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given

from cgaskin.generated import kernels as K
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import (I3, LOG_IDX, call, cl_exp, cl_vector, coefficients, covers, einf,
                                          eo, log_oracle, moderate_scale_versors, record, rel_err_sign,
                                          to_mv, versor_coefficients)
from tests.helpers.tolerances import TOL, rel_err

# ==== logarithm and exponential ===============================================================================
@covers("versor_log")
@given(S.versors())
def test_versor_log_vs_oracle(sim):
    expected, theta = log_oracle(sim)
    assume(theta < math.pi - 1e-6)                       # at a half turn the axis sign is a free choice
    got = call(K.versor_log, sim.versor())
    err = record("versor_log", rel_err(got, expected, max(1.0, float(np.abs(expected).max()))))
    assert err <= TOL.kernel


@given(moderate_scale_versors)
def test_versor_log_vs_clifford(sim):
    """exp of the returned bivector, computed by clifford, gives the versor back (up to sign)."""
    got = call(K.versor_log, versor_coefficients(sim))
    motor = cl_exp(to_mv(np.r_[got[:6], 0.0], LOG_IDX))
    dil = cl_exp(float(got[6]) * (einf ^ eo))
    err = rel_err_sign(coefficients(motor * dil), versor_coefficients(sim))
    assert err <= TOL.clifford * max(1.0, sim.magnitude)


@given(S.versors())
def test_exp_of_log_is_identity(sim):
    v = sim.versor()
    back = call(K.versor_exp, call(K.versor_log, v))
    assert record("exp(log(V)) round trip", rel_err_sign(back, v)) <= TOL.kernel


# Regression: before generator b5db720, a = (1 - th sin th / (2 (1 - cos th))) / th^2 cancelled for
# 1e-4 <= th << 1 (relative error ~1e-16 / th^2: 7e-9 at th = 1.01e-4); the series now runs to 0.2 rad.
@pytest.mark.parametrize("theta", [1e-4, 1.01e-4, 2e-4, 1e-3, 3e-3, 0.1999999, 0.2, 0.2000001, 0.5])
def test_versor_log_small_angle_precision(theta):
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(50):
        axis = rng.normal(size=3)
        sim = S.Similarity(axis / np.linalg.norm(axis), theta, rng.uniform(-10, 10, 3), 1.0)
        expected, _ = log_oracle(sim)
        worst = max(worst, rel_err(call(K.versor_log, sim.versor()), expected, max(1.0, np.abs(expected).max())))
    assert worst <= TOL.kernel, f"versor_log error {worst:.3g} at theta = {theta}"


def _bivector(axis, theta, v):
    """-1/2 (theta n I3 + v ^ e-inf): the log of a screw motion, built in clifford."""
    return -0.5 * (theta * (cl_vector(axis) * I3) + (cl_vector(v) ^ einf))


@covers("versor_exp")
@given(S.unit_axes(), S.angles(0.0, 2 * math.pi), S.translations(TOL.moderate))
def test_versor_exp_pure_motor_vs_clifford(axis, theta, v):
    biv = _bivector(axis, theta, v)
    L = np.r_[coefficients(biv, LOG_IDX[:6], "motor bivector"), 0.0]
    got = call(K.versor_exp, L)
    expected = coefficients(cl_exp(biv), what="exp(motor bivector)")
    assert record("versor_exp", rel_err(got, expected, max(1.0, np.abs(expected).max()))) <= TOL.clifford


@given(S.unit_axes(), S.angles(0.0, 2 * math.pi), S.translations(TOL.moderate), S.scales())
def test_versor_exp_with_dilation_vs_clifford(axis, theta, v, scale):
    biv = _bivector(axis, theta, v)
    lam = -0.5 * math.log(scale)
    L = np.r_[coefficients(biv, LOG_IDX[:6], "motor bivector"), lam]
    got = call(K.versor_exp, L)
    expected = coefficients(cl_exp(biv) * cl_exp(lam * (einf ^ eo)), what="exp(motor) exp(dilation)")
    assert record("versor_exp", rel_err(got, expected)) <= TOL.clifford
    # the e-inf0 part alone is the dilator of that scale
    d = call(K.versor_exp, np.r_[np.zeros(6), lam])
    assert rel_err(d, call(K.versor_dilator, scale)) <= TOL.kernel


@given(S.unit_axes(), S.angles(0.0, math.pi - 1e-6), S.translations(), S.scales())
def test_log_of_exp_is_identity(axis, theta, v, scale):
    w = theta * axis
    L = np.array([-w[2] / 2, w[1] / 2, -w[0] / 2, -v[0] / 2, -v[1] / 2, -v[2] / 2, -0.5 * math.log(scale)])
    back = call(K.versor_log, call(K.versor_exp, L))
    err = record("versor_log", rel_err(back, L, max(1.0, float(np.abs(L).max()))))
    assert err <= TOL.kernel
