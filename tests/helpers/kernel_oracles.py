"""The independent oracles of the generated-kernel tests (tests/codegen/test_kernels_*.py).

- clifford.g3c (the full 32-blade algebra in the e4/e5 basis) at moderate coordinates (|x|, |t| <= 10):
  translator 1 - t e-inf / 2, rotor cos(a/2) - sin(a/2) n I3, dilator exp(-ln(s)/2 e-inf^e0), sandwich
  down(V up(x) V~), products, reverse, inverse, exponentials by Taylor series with scaling and squaring;
- plain float64 matrices (Rodrigues rotation, uniform scale, translation) at large coordinates (up to
  1e4, scales 0.01 .. 100), where clifford's up/down lose ~EPS |x|^2;
- numpy (least squares, cross products, matrix LBS) for planes, barycentric coordinates and skinning.

Kernels are called directly (the njit scalar forms, with (12,) coefficient arrays built by clifford
wherever that keeps the test independent of the other kernels). Tolerances come from tolerances.TOL.
``covers`` marks the test that gives a kernel its oracle (tests/codegen/test_kernels_batch.py checks
that every kernel has one) and ``record`` keeps the worst relative error seen per kernel (run with
``-s``: tests/codegen/conftest.py prints it after each module).
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
from clifford import g3c
from hypothesis import strategies as st

from cgaskin.generated.layout import LOG_BLADES, MOTOR_BLADES, PLANE_BLADES, VERSOR_BLADES

from . import strategies as S
from .tolerances import TOL, rel_err

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


# ==== bookkeeping: which kernels have an oracle test, the worst error seen per kernel ====================
WORST: dict[str, float] = defaultdict(float)
COVERED: set[str] = set()


def covers(*names):
    """Mark the test that checks the kernels ``names`` against an oracle."""
    def mark(fn):
        COVERED.update(names)
        return fn
    return mark


def record(kernel: str, err: float) -> float:
    """Keep ``err`` if it is the worst seen for ``kernel``; returns it."""
    WORST[kernel] = max(WORST[kernel], float(err))
    return float(err)


# ==== comparisons and float64 oracles =========================================================================
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

