"""Every generated kernel against independent oracles.

Oracles:
- clifford.g3c (the full 32-blade algebra in the e4/e5 basis) at moderate coordinates (|x|, |t| <= 10):
  translator 1 - t e-inf / 2, rotor cos(a/2) - sin(a/2) n I3, dilator exp(-ln(s)/2 e-inf^e0), sandwich
  down(V up(x) V~), products, reverse, inverse, exponentials by Taylor series with scaling and squaring;
- plain float64 matrices (Rodrigues rotation, uniform scale, translation) at large coordinates (up to
  1e4, scales 0.01 .. 100), where clifford's up/down lose ~EPS |x|^2;
- numpy (least squares, cross products, matrix LBS) for planes, barycentric coordinates and skinning.

Kernels are called directly (the njit scalar forms, with (12,) coefficient arrays built by clifford
wherever that keeps the test independent of the other kernels). Tolerances come from tolerances.TOL;
run with ``-s`` to print the worst relative error seen per kernel.
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
from clifford import g3c
from hypothesis import assume, example, given, strategies as st

from tests.helpers import strategies as S
from cgaskin import versor as V
from cgaskin.errors import InvalidInputError
from cgaskin.generated import kernels as K
from cgaskin.generated import skinning as SK
from cgaskin.generated.layout import LOG_BLADES, MOTOR_BLADES, PLANE_BLADES, VERSOR_BLADES
from tests.helpers.tolerances import TOL, rel_err

# ==== clifford side: blades, conversions, independent constructions ========================================
e1, e2, e3, einf, eo = g3c.e1, g3c.e2, g3c.e3, g3c.einf, g3c.eo
I3 = e1 * e2 * e3
NULL_VECTORS = {"1": e1, "2": e2, "3": e3, "∞": einf, "0": eo}
ONE = g3c.layout.scalar


def cl_blade(display_name: str):
    """The blade named like the layout ('1', 'e12', 'e1∞', 'e∞0') as an outer product in index order."""
    blade = 1.0 * ONE
    if display_name != "1":
        for ch in display_name[1:]:
            blade = blade ^ NULL_VECTORS[ch]
    return blade


def _all_null_blades():
    names = ["1"]
    order = "123∞0"
    for mask in range(1, 32):
        names.append("e" + "".join(order[k] for k in range(5) if mask >> k & 1))
    return names


ALL_NAMES = _all_null_blades()
ALL_BASIS = np.stack([cl_blade(n).value for n in ALL_NAMES], axis=1)       # (32 e4/e5 coords, 32 null)
ALL_INV = np.linalg.inv(ALL_BASIS)
VERSOR_IDX = [ALL_NAMES.index(n) for n in VERSOR_BLADES]
MOTOR_IDX = [ALL_NAMES.index(n) for n in MOTOR_BLADES]
PLANE_IDX = [ALL_NAMES.index(n) for n in PLANE_BLADES]
LOG_IDX = [ALL_NAMES.index(n) for n in LOG_BLADES]


def to_mv(coefficients, index=VERSOR_IDX):
    """clifford multivector with the given coefficients on the null blades ``index``."""
    return g3c.layout.MultiVector(ALL_BASIS[:, index] @ np.asarray(coefficients, float))


def null_coefficients(mv) -> np.ndarray:
    """(32,) coefficients of a clifford multivector on the null blades (ALL_NAMES order)."""
    return ALL_INV @ mv.value


def coefficients(mv, index=VERSOR_IDX, what="multivector") -> np.ndarray:
    """Coefficients on the blades ``index``; fails if the multivector has other components."""
    c = null_coefficients(mv)
    rest = np.delete(c, index)
    scale = max(1.0, float(np.max(np.abs(c))))
    assert np.max(np.abs(rest)) <= 1e-13 * scale, f"{what} has components outside its type: {mv}"
    return c[index]


def cl_vector(x):
    return float(x[0]) * e1 + float(x[1]) * e2 + float(x[2]) * e3


def euclid(mv) -> np.ndarray:
    return mv.value[1:4].copy()


def cl_translator(t):
    return 1.0 - 0.5 * cl_vector(t) * einf


def cl_rotor(axis, angle):
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    return math.cos(angle / 2) - math.sin(angle / 2) * (cl_vector(n) * I3)


def cl_dilator(scale):
    half = 0.5 * math.log(scale)
    return math.cosh(half) - math.sinh(half) * (einf ^ eo)        # = exp(-ln(s)/2 e-inf^e0)


def cl_versor(sim: S.Similarity):
    return cl_translator(sim.translation) * cl_rotor(sim.axis, sim.angle) * cl_dilator(sim.scale)


def cl_apply(versor, x) -> np.ndarray:
    return euclid(g3c.down(versor * g3c.up(cl_vector(x)) * ~versor))


def cl_exp(bivector, order: int = 24):
    """exp by Taylor series after scaling by 2^-k, then k squarings (independent of clifford's exp)."""
    size = float(np.max(np.abs(bivector.value)))
    k = max(0, int(math.ceil(math.log2(size))) + 3) if size > 0 else 0
    x = bivector * (0.5 ** k)
    term, total = 1.0 * ONE, 1.0 * ONE
    for i in range(1, order):
        term = term * x * (1.0 / i)
        total = total + term
    for _ in range(k):
        total = total * total
    return total


def versor_coefficients(sim: S.Similarity) -> np.ndarray:
    """(12,) coefficients of T R D built by clifford (not by any cgaskin kernel)."""
    return coefficients(cl_versor(sim), what="T R D")


# ==== helpers ===============================================================================================
WORST: dict[str, float] = defaultdict(float)
COVERED: set[str] = set()


def covers(*names):
    def mark(fn):
        COVERED.update(names)
        return fn
    return mark


def record(kernel: str, err: float) -> float:
    WORST[kernel] = max(WORST[kernel], float(err))
    return float(err)


@pytest.fixture(scope="module", autouse=True)
def _print_worst_errors():
    yield
    if WORST:
        print("\nworst relative errors per kernel (this run):")
        for name in sorted(WORST):
            print(f"  {name:34s} {WORST[name]:.3g}")


def rel_err_sign(got, expected, scale=None) -> float:
    """Relative error up to an overall sign (V and -V are the same transformation)."""
    return min(rel_err(got, expected, scale), rel_err(got, -np.asarray(expected), scale))


def call(kernel, *args) -> np.ndarray:
    return np.asarray(kernel(*args), float)


def clifford_point_tol(magnitude: float) -> float:
    """clifford's up/down work in e4/e5 and lose ~EPS |x|^2 relative precision: at coordinates up to
    TOL.moderate we ask TOL.clifford, beyond that the oracle's own error grows quadratically."""
    return TOL.clifford * max(1.0, (magnitude / TOL.moderate) ** 2)


def reduced_rotation(sim: S.Similarity):
    """(theta in [0, pi], unit axis) of the same rotation as sim's (axis, angle)."""
    a = math.remainder(sim.angle, 2 * math.pi)
    return abs(a), (sim.axis if a >= 0 else -sim.axis)


def skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def screw_jacobian(w) -> np.ndarray:
    """J(w) = I + b [w]x + c [w]x^2 (t = J v), with b, c computed without cancellation."""
    th = float(np.linalg.norm(w))
    if th < 0.02:
        t2 = th * th
        b = 0.5 - t2 / 24 + t2 * t2 / 720 - t2 ** 3 / 40320
        c = 1 / 6 - t2 / 120 + t2 * t2 / 5040 - t2 ** 3 / 362880
    else:
        b = 2.0 * math.sin(th / 2) ** 2 / th ** 2
        c = (th - math.sin(th)) / th ** 3
    k = skew(w)
    return np.eye(3) + b * k + c * (k @ k)


def log_oracle(sim: S.Similarity):
    """(L (7,), theta): the logarithm of T R D from its parameters (float64 linear solve with a
    well-conditioned J for theta < pi)."""
    theta, n = reduced_rotation(sim)
    w = theta * n
    v = np.linalg.solve(screw_jacobian(w), sim.translation)
    L = np.array([-w[2] / 2, w[1] / 2, -w[0] / 2, -v[0] / 2, -v[1] / 2, -v[2] / 2, -math.log(sim.scale) / 2])
    return L, theta


moderate_versors = S.moderate_versors()
moderate_scale_versors = st.builds(S.Similarity, axis=S.unit_axes(), angle=S.angles(),
                                   translation=S.translations(TOL.moderate), scale=S.scales(0.1, 10.0))


# ==== the oracles themselves ================================================================================
def test_clifford_oracle_conventions():
    # e0 . e-inf = -1 and both are null (design.md section 2)
    assert (eo | einf)[()] == -1.0 and (einf * einf).value.max() == 0 and (eo * eo).value.max() == 0
    # a positive angle is right-handed: e1 rotated by +90 degrees about e3 is e2
    r = cl_rotor([0, 0, 1], math.pi / 2)
    np.testing.assert_allclose(euclid(r * e1 * ~r), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(cl_apply(r, [1.0, 0, 0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(cl_apply(cl_rotor([1, 0, 0], math.pi / 2), [0, 1.0, 0]), [0, 0, 1], atol=1e-15)
    # translator and dilator
    np.testing.assert_allclose(cl_apply(cl_translator([1, -2, 3]), [0.5, 0.5, 0.5]), [1.5, -1.5, 3.5], atol=1e-14)
    for s in (0.01, 0.5, 3.0, 100.0):
        np.testing.assert_allclose(cl_apply(cl_dilator(s), [0.1, 0.2, -0.3]), np.multiply(s, [0.1, 0.2, -0.3]),
                                   rtol=clifford_point_tol(0.3 * s))
        d = cl_exp(-0.5 * math.log(s) * (einf ^ eo))
        assert rel_err(d.value, cl_dilator(s).value) <= 1e-14
    # T R D applies D first, then R, then T
    sim = S.Similarity(np.array([0.0, 0.0, 1.0]), math.pi / 2, np.array([1.0, 2.0, 3.0]), 2.0)
    np.testing.assert_allclose(cl_apply(cl_versor(sim), [1.0, 0, 0]), sim.apply([1.0, 0, 0]), atol=1e-13)
    # Taylor exp of a rotation bivector is the rotor
    n = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    assert rel_err(cl_exp(-0.5 * 2.5 * (cl_vector(n) * I3)).value, cl_rotor(n, 2.5).value) <= 1e-14


@given(S.coefficient_arrays(12))
def test_to_clifford_matches_hand_built(arr):
    hand = sum((float(c) * cl_blade(name) for c, name in zip(arr, VERSOR_BLADES)), 0.0 * ONE)
    got = V.to_clifford(arr)
    assert rel_err(got.value, hand.value, max(1.0, np.abs(arr).max())) <= TOL.table
    batch = V.to_clifford(np.stack([arr, 2 * arr]))
    assert isinstance(batch, list) and len(batch) == 2
    assert rel_err(batch[1].value, 2 * hand.value, max(1.0, np.abs(arr).max())) <= TOL.table


@given(S.coefficient_arrays(12))
def test_from_clifford_matches_hand_built(arr):
    hand = sum((float(c) * cl_blade(name) for c, name in zip(arr, VERSOR_BLADES)), 0.0 * ONE)
    assert rel_err(V.from_clifford(hand), arr, max(1.0, np.abs(arr).max())) <= 1e-14
    assert rel_err(V.from_clifford(V.to_clifford(arr)), arr, max(1.0, np.abs(arr).max())) <= 1e-14
    with pytest.raises(InvalidInputError):
        V.from_clifford(hand + 0.5 * e1)                          # a vector part is not in the type
    with pytest.raises(InvalidInputError):
        V.from_clifford(hand + 0.5 * (e1 ^ eo))


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


# ==== points ===================================================================================================
@covers("sandwich_versor_point")
@given(moderate_scale_versors, S.moderate_points())
def test_sandwich_versor_point_vs_clifford(sim, x):
    v = versor_coefficients(sim)
    got = call(K.sandwich_versor_point, v, x)
    expected = cl_apply(cl_versor(sim), x)
    mag = max(1.0, float(np.abs(expected).max()), sim.scale * float(np.abs(x).max()))
    assert record("sandwich_versor_point (clifford)", rel_err(got, expected, mag)) <= clifford_point_tol(mag)


@given(S.versors(), S.points())
def test_sandwich_versor_point_large(sim, x):
    got = call(K.sandwich_versor_point, sim.versor(), x)
    expected = sim.apply(x)
    mag = max(sim.magnitude, sim.scale * float(np.abs(x).max()))
    assert record("sandwich_versor_point", rel_err(got, expected, mag)) <= TOL.large


@covers("versor_to_affine")
@given(moderate_scale_versors)
def test_versor_to_affine_vs_clifford(sim):
    a = call(K.versor_to_affine, versor_coefficients(sim)).reshape(3, 4)
    cv = cl_versor(sim)
    origin = cl_apply(cv, np.zeros(3))
    columns = [cl_apply(cv, np.eye(3)[j]) - origin for j in range(3)]
    expected = np.column_stack(columns + [origin])
    mag = max(1.0, sim.magnitude)
    assert record("versor_to_affine (clifford)", rel_err(a, expected, mag)) <= clifford_point_tol(mag + sim.scale)


@given(S.versors())
def test_versor_to_affine_large(sim):
    a = call(K.versor_to_affine, sim.versor()).reshape(3, 4)
    err = max(rel_err(a[:, :3], sim.linear(), sim.scale), rel_err(a[:, 3], sim.translation, sim.magnitude))
    assert record("versor_to_affine", err) <= TOL.large


@covers("affine_point")
@given(S.coefficient_arrays(12, 100.0), S.points())
def test_affine_point(a, x):
    got = call(K.affine_point, a, x)
    m = a.reshape(3, 4)
    expected = m[:, :3] @ x + m[:, 3]
    scale = max(1e-300, float(np.max(np.abs(m[:, :3]) @ np.abs(x) + np.abs(m[:, 3]))))
    assert record("affine_point", rel_err(got, expected, scale)) <= TOL.kernel


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


# ==== skinning loops ==========================================================================================
def _numpy_lbs(rest, joints, weights, affines):
    a = affines.reshape(-1, 3, 4)
    blended = np.einsum("nk,nkij->nij", weights, a[joints])
    return np.einsum("nij,nj->ni", blended[:, :, :3], rest) + blended[:, :, 3]


@covers("skin_blend", "skin_blend_parallel")
@given(S.skinned_meshes())
def test_skin_blend_matches_numpy_lbs(mesh):
    rest, joints, weights, bones = mesh
    affines = np.stack([call(K.versor_to_affine, b.versor()) for b in bones])
    out, out_par = np.empty_like(rest), np.empty_like(rest)
    SK.skin_blend(rest, joints, weights, affines, out)
    SK.skin_blend_parallel(rest, joints, weights, affines, out_par)
    np.testing.assert_array_equal(out, out_par)
    mag = max(1.0, max(b.magnitude for b in bones) * max(1.0, float(np.abs(rest).max())))
    assert record("skin_blend", rel_err(out, _numpy_lbs(rest, joints, weights, affines), mag)) <= TOL.kernel
    # and against matrix LBS of the same similarities (no versor on that side)
    mats = np.stack([b.matrix()[:3].ravel() for b in bones])
    assert record("skin_blend", rel_err(out, _numpy_lbs(rest, joints, weights, mats), mag)) <= TOL.large


def test_every_kernel_is_tested():
    skinning = {name for name in dir(SK) if name.startswith("skin_") and callable(getattr(SK, name))}
    missing = (set(K.KERNEL_NAMES) | skinning) - COVERED
    assert not missing, f"kernels without an oracle test: {sorted(missing)}"


# ==== batch forms ============================================================================================
_RNG = np.random.default_rng(11)
_SIMS = [S.Similarity(ax / np.linalg.norm(ax), ang, t, s) for ax, ang, t, s in zip(
    _RNG.normal(size=(5, 3)), _RNG.uniform(-6, 6, 5), _RNG.uniform(-100, 100, (5, 3)), np.exp(_RNG.uniform(-4, 4, 5)))]


def _batch_inputs(name):
    vs = np.stack([s.versor() for s in _SIMS])
    pts = _RNG.uniform(-50, 50, (5, 3))
    normals = _RNG.normal(size=(5, 3))
    planes = np.column_stack([normals / np.linalg.norm(normals, axis=1, keepdims=True), _RNG.uniform(-9, 9, 5)])
    return {
        "versor_translator": (pts,),
        "versor_rotor": (_RNG.normal(size=(5, 3)), _RNG.uniform(-6, 6, 5)),
        "versor_rotor_quaternion": (_RNG.normal(size=(5, 4)),),
        "versor_dilator": (np.exp(_RNG.uniform(-4, 4, 5)),),
        "versor_from_matrix": (np.stack([s.matrix().ravel() for s in _SIMS]),),
        "gp_motor_motor": (vs[:, :8], vs[::-1, :8].copy()),
        "gp_versor_versor": (vs, vs[::-1].copy()),
        "reverse_versor": (vs,), "inverse_versor": (vs,), "versor_residual": (vs,),
        "versor_normalise": (vs * 1.7,), "versor_to_affine": (vs,), "versor_log": (vs,),
        "sandwich_versor_point": (vs, pts),
        "affine_point": (_RNG.normal(size=(5, 12)), pts),
        "plane_from_normal_distance": (_RNG.normal(size=(5, 3)), _RNG.uniform(-9, 9, 5)),
        "plane_from_points": (pts, pts + _RNG.normal(size=(5, 3)), pts + _RNG.normal(size=(5, 3))),
        "plane_transform": (vs, planes),
        "point_plane_distance": (planes, pts),
        "segment_plane": (planes, pts, -pts),
        "barycentric": (pts, pts + _RNG.normal(size=(5, 3)), pts + _RNG.normal(size=(5, 3)), pts + 0.3),
        "versor_exp": (_RNG.normal(size=(5, 7)),),
    }[name]


# (plane_from_normal_distance_batch used to shadow its input `n` with the row index: fixed in b5db720)
@pytest.mark.parametrize("name", K.KERNEL_NAMES)
def test_batch_kernel_matches_scalar(name):
    args = _batch_inputs(name)
    scalar = getattr(K, name)
    rows = [np.atleast_1d(np.asarray(scalar(*(a[i] for a in args)), float)) for i in range(5)]
    expected = np.stack(rows)
    out = np.empty(expected.shape)
    getattr(K, name + "_batch")(*args, out)
    np.testing.assert_array_equal(out, expected)
