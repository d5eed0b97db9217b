"""Logarithm and exponential of similarity versors (screw twist plus log scale)."""
from __future__ import annotations

import sympy
from sympy import Piecewise, Rational, cos, sin, sqrt, atan2, log

from . import algebra
from .ir import KernelBuilder
from .kernel_parts import HALF, dilator, translator
from .layouts import LOG, ROTOR, VERSOR

# Below these, closed forms divide 0 by 0: use Taylor series accurate to far below 1e-16.
SMALL_ANGLE = 1e-4
SMALL_SINE = 1e-8
# Below this angle the closed forms with θ − sin θ or 1 − x cot x cancel (relative error ~ε/θ²):
# use their Taylor series, whose first omitted term is < 1e-17 here.
SERIES_ANGLE = 0.2


def _series(x2, coefficients):
    """Σ c_k x2^k by Horner's rule (x2 a symbol or expression, coefficients exact rationals)."""
    acc = sympy.Integer(0)
    for c in reversed(coefficients):
        acc = acc * x2 + c
    return acc


def versor_log():
    k = KernelBuilder(
        "versor_log",
        "Logarithm of a similarity versor V = exp(Λ_M) exp(−½ ln s e∞0): Λ_M = −½(ω₁e23 − ω₂e13 + "
        "ω₃e12 + v·e∞) is the motor's bivector (the screw twist (ω, v), t = J(ω) v) and the last "
        "coefficient is −½ ln s. Returns the 7 coefficients on (e12, e13, e23, e1∞, e2∞, e3∞, e∞0). "
        "V is normalised first; the rotation angle is taken in [0, π].")
    v = k.multivector("v", VERSOR)
    names = ("p", "r0", "r12", "r13", "r23", "kappa", "lam_inv", "t1", "t2", "t3",
             "qx", "qy", "qz", "qw", "sin_half", "theta", "f", "w1", "w2", "w3", "a")
    sy = dict(zip(names, k.intermediate(*names)))
    P = [v[VERSOR.index(b)] for b in ROTOR]
    Q = [v[VERSOR.index(b)] for b in ("eio", "e12io", "e13io", "e23io")]
    k.let(sy["p"], sqrt(sum(c ** 2 for c in P)))
    # take the rotor with w >= 0 so that the angle is in [0, π]
    sgn = Piecewise((-1, P[0] < 0), (1, True))
    for name, c in zip(("r0", "r12", "r13", "r23"), P):
        k.let(sy[name], sgn * c / sy["p"])
    r = [sy[n] for n in ("r0", "r12", "r13", "r23")]
    qr = sum(qc * rc for qc, rc in zip(Q, r))
    k.let(sy["kappa"], -qr * sgn / sy["p"])
    k.let(sy["lam_inv"], sgn / (sy["p"] + qr * sgn))
    R = k.mv(ROTOR, r)
    inf_part = k.mv(("e1i", "e2i", "e3i", "e123i"), [v[VERSOR.index(b)] for b in ("e1i", "e2i", "e3i", "e123i")])
    tinf = inf_part * R.reverse()
    for name, b in zip(("t1", "t2", "t3"), ("e1i", "e2i", "e3i")):
        k.let(sy[name], -2 * tinf[b].as_expr() * sy["lam_inv"])
    for name, value in zip(("qx", "qy", "qz", "qw"), (-sy["r23"], sy["r13"], -sy["r12"], sy["r0"])):
        k.let(sy[name], value)
    qx, qy, qz, qw = (sy[n] for n in ("qx", "qy", "qz", "qw"))
    k.let(sy["sin_half"], sqrt(qx ** 2 + qy ** 2 + qz ** 2))
    k.let(sy["theta"], 2 * atan2(sy["sin_half"], qw))
    # ω = θ n = q_xyz · θ / sin(θ/2); the ratio tends to 2/w (error ~ sin² ≤ 1e-16 below SMALL_SINE)
    k.let(sy["f"], Piecewise((2 / qw, sy["sin_half"] < SMALL_SINE), (sy["theta"] / sy["sin_half"], True)))
    for name, qc in zip(("w1", "w2", "w3"), (qx, qy, qz)):
        k.let(sy[name], qc * sy["f"])
    th = sy["theta"]
    # J(ω)⁻¹ = I − ½[ω]× + a [ω]×², a = (1 − (θ/2) cot(θ/2)) / θ²; with x = θ/2 the series of
    # 1 − x cot x is Σ 2^2k |B_2k| x^2k / (2k)!, so a = 1/12 + x²/180 + x⁴/1890 + ...
    x2 = th ** 2 / 4
    a_series = _series(x2, [Rational(1, 12), Rational(1, 180), Rational(1, 1890), Rational(1, 18900),
                            Rational(1, 187110), Rational(691, 2554051500)])
    k.let(sy["a"], Piecewise((a_series, th < SERIES_ANGLE),
                             ((1 - (th / 2) * cos(th / 2) / sin(th / 2)) / th ** 2, True)))
    w = sympy.Matrix([sy["w1"], sy["w2"], sy["w3"]])
    t = sympy.Matrix([sy["t1"], sy["t2"], sy["t3"]])
    wx = sympy.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    vt = t - wx * t / 2 + sy["a"] * (wx * (wx * t))
    log_s = log((1 + sy["kappa"]) / (1 - sy["kappa"]))           # s = (1 + tanh)/(1 − tanh)
    k.output([f"L[{algebra.blade_display(algebra.mask_of(b))}]" for b in LOG],
             [-w[2] / 2, w[1] / 2, -w[0] / 2, -vt[0] / 2, -vt[1] / 2, -vt[2] / 2, -log_s / 2])
    return k.build()


def versor_exp():
    k = KernelBuilder(
        "versor_exp",
        "Inverse of versor_log: L (7,) on (e12, e13, e23, e1∞, e2∞, e3∞, e∞0) -> exp(Λ_M) exp(L_e∞0 e∞0), "
        "with exp(Λ_M) = T(J(ω) v) R(ω) the screw motion of twist (ω, v), "
        "J(ω) = I + b [ω]× + c [ω]×², b = (1 − cos θ)/θ², c = (θ − sin θ)/θ³.")
    L = k.array("L", 7)
    names = ("w1", "w2", "w3", "v1", "v2", "v3", "theta", "cos_half", "sinc_half", "b", "c",
             "t1", "t2", "t3", "ch", "sh")
    sy = dict(zip(names, k.intermediate(*names)))
    for name, value in zip(("w1", "w2", "w3", "v1", "v2", "v3"),
                           (-2 * L[2], 2 * L[1], -2 * L[0], -2 * L[3], -2 * L[4], -2 * L[5])):
        k.let(sy[name], value)
    w = sympy.Matrix([sy["w1"], sy["w2"], sy["w3"]])
    vv = sympy.Matrix([sy["v1"], sy["v2"], sy["v3"]])
    th = sy["theta"]
    k.let(th, sqrt(w.dot(w)))
    k.let(sy["cos_half"], cos(th / 2))
    k.let(sy["sinc_half"], Piecewise((HALF - th ** 2 / 48, th < SMALL_ANGLE), (sin(th / 2) / th, True)))
    # b = (1 − cos θ)/θ² = 2 (sin(θ/2)/θ)² has no cancellation; c = (θ − sin θ)/θ³ needs its series
    k.let(sy["b"], 2 * sy["sinc_half"] ** 2)
    c_series = _series(th ** 2, [Rational(1, 6), Rational(-1, 120), Rational(1, 5040), Rational(-1, 362880),
                                 Rational(1, 39916800), Rational(-1, 6227020800)])
    k.let(sy["c"], Piecewise((c_series, th < SERIES_ANGLE), ((th - sin(th)) / th ** 3, True)))
    wx = sympy.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    t = vv + sy["b"] * (wx * vv) + sy["c"] * (wx * (wx * vv))
    for i, name in enumerate(("t1", "t2", "t3")):
        k.let(sy[name], t[i])
    k.let(sy["ch"], sympy.cosh(L[6]))
    k.let(sy["sh"], -sympy.sinh(L[6]))
    sc = k.poly(sy["sinc_half"])
    w1, w2, w3 = (k.poly(sy[n]) for n in ("w1", "w2", "w3"))
    R = k.mv(ROTOR, [k.poly(sy["cos_half"]), -sc * w3, sc * w2, -sc * w1])
    V = translator(k, (sy["t1"], sy["t2"], sy["t3"])) * R * dilator(k, sy["ch"], sy["sh"])
    k.output_multivector("V", V, VERSOR)
    return k.build()
