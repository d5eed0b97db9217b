"""Versor kernels the kernel language cannot say yet: constructors with named intermediates (rotor,
dilator, from a matrix by Shepperd's branches), the residual and normalise. The translator and the
products (gp, reverse, inverse) are written in the language (``kernels_language``)."""
from __future__ import annotations

import sympy
from sympy import Piecewise, cos, sin, sqrt

from .ir import KernelBuilder
from .kernel_parts import HALF, dilator, rotor_from_quaternion, translator
from .layouts import ROTOR, VERSOR


# ---- construction -------------------------------------------------------------------------------
def versor_rotor():
    k = KernelBuilder("versor_rotor",
                      "Rotor about ``axis`` (3,), any nonzero length, by ``angle`` radians (right-handed).")
    a = k.array("axis", 3)
    angle = k.scalar("angle")
    inv_len, c, s = k.intermediate("inv_len", "c", "s")
    k.let(inv_len, 1 / sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2))
    k.let(c, cos(angle * HALF))
    k.let(s, sin(angle * HALF) * inv_len)
    n1, n2, n3 = (k.poly(x) for x in a)
    R = k.mv(ROTOR, [k.poly(c), -k.poly(s) * n3, k.poly(s) * n2, -k.poly(s) * n1])
    k.output_multivector("R", R, VERSOR)
    return k.build()


def versor_rotor_quaternion():
    k = KernelBuilder("versor_rotor_quaternion",
                      "Rotor of the quaternion q = (x, y, z, w) (normalised here): w − x e23 + y e13 − z e12.")
    q = k.array("q", 4)
    inv = k.intermediate("inv_len")[0]
    k.let(inv, 1 / sqrt(sum(c ** 2 for c in q)))
    k.output_multivector("R", rotor_from_quaternion(k, q), VERSOR, scale=inv)
    return k.build()


def versor_dilator():
    k = KernelBuilder("versor_dilator",
                      "Dilator about the origin by factor ``scale`` > 0: apply(D, x) = scale · x. "
                      "D = cosh(ln s/2) − sinh(ln s/2) e∞0, written with √s to avoid log/exp.")
    s = k.scalar("scale")
    root, ch, sh = k.intermediate("root", "ch", "sh")
    k.let(root, sqrt(s))
    k.let(ch, (s + 1) / (2 * root))
    k.let(sh, (s - 1) / (2 * root))
    k.output_multivector("D", dilator(k, ch, sh), VERSOR)
    return k.build()


def _shepperd(r):
    """Quaternion (x, y, z, w) of a rotation matrix r[i][j], branching on the largest of
    (trace, r00, r11, r22) so that the square root never sees cancellation (180° safe)."""
    tr = r[0][0] + r[1][1] + r[2][2]
    branches = [
        (tr > 0, sqrt(tr + 1) * 2, lambda S: ((r[2][1] - r[1][2]) / S, (r[0][2] - r[2][0]) / S,
                                              (r[1][0] - r[0][1]) / S, S / 4)),
        (sympy.And(r[0][0] >= r[1][1], r[0][0] >= r[2][2]), sqrt(1 + r[0][0] - r[1][1] - r[2][2]) * 2,
         lambda S: (S / 4, (r[0][1] + r[1][0]) / S, (r[0][2] + r[2][0]) / S, (r[2][1] - r[1][2]) / S)),
        (r[1][1] >= r[2][2], sqrt(1 + r[1][1] - r[0][0] - r[2][2]) * 2,
         lambda S: ((r[0][1] + r[1][0]) / S, S / 4, (r[1][2] + r[2][1]) / S, (r[0][2] - r[2][0]) / S)),
        (sympy.true, sqrt(1 + r[2][2] - r[0][0] - r[1][1]) * 2,
         lambda S: ((r[0][2] + r[2][0]) / S, (r[1][2] + r[2][1]) / S, S / 4, (r[1][0] - r[0][1]) / S)),
    ]
    return [Piecewise(*[(f(S)[i], cond) for cond, S, f in branches], evaluate=False) for i in range(4)]


def versor_from_matrix():
    k = KernelBuilder("versor_from_matrix",
                      "Versor T R D of a 4x4 similarity matrix m (16,) row-major: uniform scale "
                      "s = cbrt(det), rotation by Shepperd's method on the linear part / s.")
    m = k.array("m", 16)
    M = [[m[4 * i + j] for j in range(4)] for i in range(3)]
    s, inv_s, ch, sh, *q = k.intermediate("s", "inv_s", "ch", "sh", "qx", "qy", "qz", "qw")
    det = sympy.Matrix(3, 3, lambda i, j: M[i][j]).det(method="berkowitz")
    k.let(s, sympy.cbrt(det))
    k.let(inv_s, 1 / s)
    r = [[M[i][j] * inv_s for j in range(3)] for i in range(3)]
    for sym, value in zip(q, _shepperd(r)):
        k.let(sym, value)
    k.let(ch, (s + 1) / (2 * sqrt(s)))
    k.let(sh, (s - 1) / (2 * sqrt(s)))
    V = translator(k, [M[0][3], M[1][3], M[2][3]]) * rotor_from_quaternion(k, q) * dilator(k, ch, sh)
    k.output_multivector("V", V, VERSOR)
    return k.build()


# ---- how far from a versor, and back to one ---------------------------------------------------
def versor_residual():
    k = KernelBuilder("versor_residual",
                      "How far V is from a similarity versor: (largest |non-scalar coefficient of V Ṽ|,"
                      " ⟨V Ṽ⟩₀). A versor has the first 0 and the second > 0.")
    v = k.multivector("v", VERSOR)
    V = k.mv(VERSOR, v)
    VV = V * V.reverse()
    others = [VV.terms[m].as_expr() for m in VV.blades if m != 0]
    k.output(["max_abs(VV~ - <VV~>0)", "<VV~>0"], [sympy.Max(*[sympy.Abs(o) for o in others]), VV["s"]])
    return k.build()


def versor_normalise():
    k = KernelBuilder(
        "versor_normalise",
        "Nearest similarity versor T R D(s) with ⟨V Ṽ⟩₀ = 1 to any 12-blade multivector V (e.g. a "
        "linear blend): V = T R D has rotor part c R, e∞0 part −sh R, e∞ part −½(c − sh) t e∞ R. So "
        "R = rotor part normalised, tanh(ln s/2) = sh/c, t read off the e∞ part times R̃.")
    v = k.multivector("v", VERSOR)
    p, *rest = k.intermediate("p", "r0", "r12", "r13", "r23", "kappa", "ch", "sh", "lam_inv", "t1", "t2", "t3")
    r, (kappa, ch, sh, lam_inv, t1, t2, t3) = rest[:4], rest[4:]
    P = [v[VERSOR.index(b)] for b in ROTOR]
    Q = [v[VERSOR.index(b)] for b in ("eio", "e12io", "e13io", "e23io")]
    k.let(p, sqrt(sum(c ** 2 for c in P)))
    for sym, c in zip(r, P):
        k.let(sym, c / p)
    # rotor part = λ c R, e∞0 part = −λ sh R  =>  sh/c = −(Q·R)/p; |sh/c| < 1 for any real scale
    k.let(kappa, -sum(qc * rc for qc, rc in zip(Q, r)) / p)
    k.let(ch, 1 / sqrt(1 - kappa ** 2))
    k.let(sh, kappa * ch)
    k.let(lam_inv, 1 / (p + sum(qc * rc for qc, rc in zip(Q, r))))      # 1 / (λ (c − sh))
    R = k.mv(ROTOR, r)
    inf_part = k.mv(("e1i", "e2i", "e3i", "e123i"), [v[VERSOR.index(b)] for b in ("e1i", "e2i", "e3i", "e123i")])
    tinf = inf_part * R.reverse()                                      # = −½ λ (c − sh) t e∞
    for sym, b in zip((t1, t2, t3), ("e1i", "e2i", "e3i")):
        k.let(sym, -2 * tinf[b].as_expr() * lam_inv)
    out = translator(k, (t1, t2, t3)) * R * dilator(k, ch, sh)
    k.output_multivector("V", out, VERSOR)
    return k.build()
