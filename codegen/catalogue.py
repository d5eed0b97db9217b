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

import sympy
from sympy import Piecewise, Rational, cos, sin, sqrt, atan2, log

from . import algebra
from .ir import CodegenError, KernelBuilder
from .symbolic import MV, up

VERSOR = ("s", "e12", "e13", "e23", "e1i", "e2i", "e3i", "e123i", "eio", "e12io", "e13io", "e23io")
MOTOR = VERSOR[:8]
ROTOR = ("s", "e12", "e13", "e23")
PLANE = ("e1", "e2", "e3", "ei")                 # dual plane n + d e∞ stored as (n1, n2, n3, d)
LOG = ("e12", "e13", "e23", "e1i", "e2i", "e3i", "eio")
AFFINE_LABELS = tuple(f"A[{r},{c}]" for r in range(3) for c in range(4))
HALF = Rational(1, 2)

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


def _euclid(k, mv, blades=("e1", "e2", "e3")):
    return [mv[b] for b in blades]


def _rotor_from_quaternion(k, q):
    x, y, z, w = (k.poly(c) for c in q)
    return k.mv(ROTOR, [w, -z, y, -x])


def _translator(k, t):
    t1, t2, t3 = (k.poly(c) for c in t)
    return k.mv(("s", "e1i", "e2i", "e3i"), [1, -t1 * HALF, -t2 * HALF, -t3 * HALF])


def _dilator(k, cosh_half, sinh_half):
    return k.mv(("s", "eio"), [k.poly(cosh_half), -k.poly(sinh_half)])


def _down(k, X: MV):
    """Euclidean point of a conformal point: Euclidean part over the e0 coefficient."""
    w = X["eo"]
    return [sympy.Mul(c.as_expr(), sympy.Pow(w.as_expr(), -1)) for c in _euclid(k, X)]


# ---- construction -------------------------------------------------------------------------------
def versor_translator():
    k = KernelBuilder("versor_translator", "Translator T(t) = 1 − ½ t e∞ as a versor; t : (3,).")
    t = k.array("t", 3)
    k.output_multivector("T", _translator(k, t), VERSOR)
    return k.build()


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
    k.output_multivector("R", _rotor_from_quaternion(k, q), VERSOR, scale=inv)
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
    k.output_multivector("D", _dilator(k, ch, sh), VERSOR)
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
    V = _translator(k, [M[0][3], M[1][3], M[2][3]]) * _rotor_from_quaternion(k, q) * _dilator(k, ch, sh)
    k.output_multivector("V", V, VERSOR)
    return k.build()


# ---- products ------------------------------------------------------------------------------------
def gp_motor_motor():
    k = KernelBuilder("gp_motor_motor", "Geometric product a b of two motors (b applies first).")
    a, b = k.multivector("a", MOTOR), k.multivector("b", MOTOR)
    k.output_multivector("ab", k.mv(MOTOR, a) * k.mv(MOTOR, b), MOTOR)
    return k.build()


def gp_versor_versor():
    k = KernelBuilder("gp_versor_versor", "Geometric product a b of two versors (b applies first).")
    a, b = k.multivector("a", VERSOR), k.multivector("b", VERSOR)
    k.output_multivector("ab", k.mv(VERSOR, a) * k.mv(VERSOR, b), VERSOR)
    return k.build()


def reverse_versor():
    k = KernelBuilder("reverse_versor", "Reverse Ṽ (grades 2 and 3 change sign).")
    v = k.multivector("v", VERSOR)
    k.output_multivector("rev", k.mv(VERSOR, v).reverse(), VERSOR)
    return k.build()


def inverse_versor():
    k = KernelBuilder("inverse_versor", "Inverse Ṽ / ⟨V Ṽ⟩₀ (exact for versors, whose V Ṽ is a scalar).")
    v = k.multivector("v", VERSOR)
    V = k.mv(VERSOR, v)
    norm = (V * V.reverse())["s"].as_expr()
    k.output_multivector("inv", V.reverse(), VERSOR, scale=1 / norm)
    return k.build()


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
    out = _translator(k, (t1, t2, t3)) * R * _dilator(k, ch, sh)
    k.output_multivector("V", out, VERSOR)
    return k.build()


# ---- points: direct sandwich and the hoisted affine form ------------------------------------------
E_PAIRS = (("s", "eio"), ("e12", "e12io"), ("e13", "e13io"), ("e23", "e23io"))


def _idempotent_versor(k, v):
    """The versor rewritten on the idempotents P± = (1 ± e∞0)/2: each pair (a, a e∞0) becomes
    p = a + b on P+ and m = a − b on P−. Products of P+ and P− vanish, so sandwiches expand into
    sums of products of p's and m's with no cancellation between the halves of a dilator:
    relative error ~ε·s instead of ~ε·s² (design.md §3.4). Declares the intermediates."""
    pm = []
    for a, b in E_PAIRS:
        p_sym, m_sym = k.intermediate(f"{v[0].name[:-2]}_p{a}", f"{v[0].name[:-2]}_m{a}")
        va, vb = v[VERSOR.index(a)], v[VERSOR.index(b)]
        k.let(p_sym, va + vb)
        k.let(m_sym, va - vb)
        pm.append((a, b, p_sym, m_sym))
    values = list(v)
    for a, b, p_sym, m_sym in pm:
        values[VERSOR.index(a)] = (k.poly(p_sym) + k.poly(m_sym)) * HALF
        values[VERSOR.index(b)] = (k.poly(p_sym) - k.poly(m_sym)) * HALF
    return k.mv(VERSOR, values)


def _sandwich_point(k, v, x):
    V = _idempotent_versor(k, v)
    return V * up(k.ring, [k.poly(c) for c in x]) * V.reverse()


def sandwich_versor_point():
    k = KernelBuilder("sandwich_versor_point",
                      "down(V up(x) Ṽ): the full sandwich on one point (use versor_to_affine for many).")
    v, x = k.multivector("v", VERSOR), k.array("x", 3)
    k.output(["x'[0]", "x'[1]", "x'[2]"], _down(k, _sandwich_point(k, v, x)))
    return k.build()


def hoist_affine(k, X, x_syms):
    """Split down(X) with X polynomial in the per-vertex symbols x into a per-bone affine map.

    Returns (A (3x4 expressions), weight): down(X) = A[:, :3] x + A[:, 3]. Raises CodegenError when
    the e0 weight depends on x or the Euclidean part is not affine in x (then no exact hoist exists).
    """
    ring = k.ring
    idx = [ring.symbols.index(s) for s in x_syms]
    weight = X["eo"]
    if any(any(mon[i] for i in idx) for mon in weight.monoms()):
        raise CodegenError(f"{k.name}: the point weight depends on the point; cannot hoist")
    rows = []
    for c in _euclid(k, X):
        by_degree: dict[int, object] = {}
        for mon, coef in c.terms():
            degrees = [mon[i] for i in idx]
            if sum(degrees) > 1:
                raise CodegenError(f"{k.name}: the sandwich is not affine in the point; cannot hoist")
            col = degrees.index(1) if sum(degrees) else 3
            stripped = tuple(0 if i in idx else e for i, e in enumerate(mon))
            by_degree[col] = by_degree.get(col, ring.zero) + ring({stripped: coef})
        rows.append([by_degree.get(col, ring.zero) for col in range(4)])
    return rows, weight


def versor_to_affine():
    k = KernelBuilder("versor_to_affine",
                      "The hoisted form of the point sandwich: down(V up(x) Ṽ) = A[:, :3] x + A[:, 3] "
                      "for every x, found by collecting V up(x) Ṽ by powers of x (the e0 weight and the "
                      "x² terms drop out of the Euclidean part). Returns A (3, 4) row-major.")
    v, x = k.multivector("v", VERSOR), k.array("x", 3)
    rows, weight = hoist_affine(k, _sandwich_point(k, v, x), x)
    k.eliminate("x")
    inv_w = k.intermediate("inv_w")[0]
    k.let(inv_w, 1 / weight.as_expr())
    k.output(AFFINE_LABELS, [e.as_expr() * inv_w for row in rows for e in row], shape=(3, 4))
    return k.build()


def affine_point():
    k = KernelBuilder("affine_point", "The per-vertex half of the hoist: A[:, :3] x + A[:, 3]; A (12,) row-major.")
    a, x = k.array("a", 12), k.array("x", 3)
    k.output(["x'[0]", "x'[1]", "x'[2]"],
             [a[4 * r] * x[0] + a[4 * r + 1] * x[1] + a[4 * r + 2] * x[2] + a[4 * r + 3] for r in range(3)])
    return k.build()


# ---- planes, distances, meets, barycentric ---------------------------------------------------------
def plane_from_normal_distance():
    k = KernelBuilder("plane_from_normal_distance",
                      "Dual plane n̂ + d e∞ (n normalised, d scaled to match) of {x : n·x = d}.")
    n, d = k.array("n", 3), k.scalar("d")
    inv = k.intermediate("inv_len")[0]
    k.let(inv, 1 / sqrt(sum(c ** 2 for c in n)))
    P = k.mv(PLANE, [n[0], n[1], n[2], d])
    k.output_multivector("plane", P, PLANE, scale=inv)
    return k.build()


def plane_from_points():
    k = KernelBuilder("plane_from_points",
                      "Dual plane through a, b, c (normal along (b−a)×(c−a)), computed relative to a for "
                      "accuracy far from the origin: π' = −(e0 ∧ up(b−a) ∧ up(c−a) ∧ e∞)*, then "
                      "normalised and moved back by d = n̂·a.")
    a, b, c = k.array("a", 3), k.array("b", 3), k.array("c", 3)
    # the edge vectors are intermediates, so that the products below stay in relative coordinates
    # (expanding b − a into the products would reintroduce absolute ones: error ~ε|a|²)
    u = k.intermediate("u0", "u1", "u2")
    w = k.intermediate("w0", "w1", "w2")
    n1, n2, n3, inv = k.intermediate("n1", "n2", "n3", "inv_len")
    for syms, other in ((u, b), (w, c)):
        for s_, oi, ai in zip(syms, other, a):
            k.let(s_, oi - ai)
    o = MV(k.ring, {algebra.mask_of("eo"): k.ring.one})
    inf = MV(k.ring, {algebra.mask_of("ei"): k.ring.one})
    U = up(k.ring, [k.poly(e) for e in u])
    W = up(k.ring, [k.poly(e) for e in w])
    P = -((o ^ U ^ W ^ inf).dual())
    if P["ei"] != 0:
        raise CodegenError("plane through the origin must have no e∞ part")
    for sym, e in zip((n1, n2, n3), _euclid(k, P)):
        k.let(sym, e)
    k.let(inv, 1 / sqrt(n1 ** 2 + n2 ** 2 + n3 ** 2))
    k.output(["plane[e1]", "plane[e2]", "plane[e3]", "plane[e∞]"],
             [n1 * inv, n2 * inv, n3 * inv, (n1 * a[0] + n2 * a[1] + n3 * a[2]) * inv])
    return k.build()


def plane_transform():
    k = KernelBuilder("plane_transform", "The plane moved by a versor: V π Ṽ, renormalised to a unit normal.")
    v, p = k.multivector("v", VERSOR), k.multivector("plane", PLANE)
    inv = k.intermediate("inv_len")[0]
    V = _idempotent_versor(k, v)
    moved = V * k.mv(PLANE, p) * V.reverse()
    n = _euclid(k, moved)
    k.let(inv, 1 / sqrt(sum(c.as_expr() ** 2 for c in n)))
    k.output_multivector("plane", moved.grade(1), PLANE, scale=inv)
    return k.build()


def point_plane_distance():
    k = KernelBuilder("point_plane_distance",
                      "Signed distance up(x)·π = n·x − d of a point from a unit dual plane π = n + d e∞.")
    p, x = k.multivector("plane", PLANE), k.array("x", 3)
    X = up(k.ring, [k.poly(c) for c in x])
    k.output(["distance"], [X.lc(k.mv(PLANE, p))["s"]])
    return k.build()


def segment_plane():
    k = KernelBuilder("segment_plane",
                      "Where segment a→b meets plane π: t = d_a / (d_a − d_b) with d the signed distances "
                      "up(·)·π, and the point a + t (b − a). t is outside [0, 1] when the segment misses.")
    p, a, b = k.multivector("plane", PLANE), k.array("a", 3), k.array("b", 3)
    P = k.mv(PLANE, p)
    da, db, t = k.intermediate("da", "db", "t")
    k.let(da, up(k.ring, [k.poly(c) for c in a]).lc(P)["s"])
    k.let(db, up(k.ring, [k.poly(c) for c in b]).lc(P)["s"])
    k.let(t, da / (da - db))
    k.output(["t", "x[0]", "x[1]", "x[2]"], [t] + [ai + t * (bi - ai) for ai, bi in zip(a, b)])
    return k.build()


def barycentric():
    k = KernelBuilder("barycentric",
                      "Barycentric coordinates (λa, λb, λc) of p projected on triangle abc, relative to a: "
                      "with u = b−a, w = c−a, q = p−a: λb = (q∧w)·(u∧w)~/|u∧w|², λc = (u∧q)·(u∧w)~/|u∧w|².")
    a, b, c, pt = (k.array(n, 3) for n in ("a", "b", "c", "p"))
    ub, wb, qb = (k.intermediate(*(f"{n}{i}" for i in range(3))) for n in ("u", "w", "q"))
    for syms, other in ((ub, b), (wb, c), (qb, pt)):
        for s_, oi, ai in zip(syms, other, a):
            k.let(s_, oi - ai)
    vec = lambda syms: k.mv(("e1", "e2", "e3"), syms)  # noqa: E731
    U, W, Q = vec(ub), vec(wb), vec(qb)
    area = U ^ W
    area_rev = area.reverse()
    inv = k.intermediate("inv_area2")[0]
    k.let(inv, 1 / (area * area_rev)["s"].as_expr())
    lb = ((Q ^ W) * area_rev)["s"].as_expr() * inv
    lc = ((U ^ Q) * area_rev)["s"].as_expr() * inv
    k.output(["λa", "λb", "λc"], [1 - lb - lc, lb, lc])
    return k.build()


# ---- logarithm and exponential -----------------------------------------------------------------------
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
    V = _translator(k, (sy["t1"], sy["t2"], sy["t3"])) * R * _dilator(k, sy["ch"], sy["sh"])
    k.output_multivector("V", V, VERSOR)
    return k.build()


KERNELS = (versor_translator, versor_rotor, versor_rotor_quaternion, versor_dilator, versor_from_matrix,
           gp_motor_motor, gp_versor_versor, reverse_versor, inverse_versor, versor_residual,
           versor_normalise, sandwich_versor_point, versor_to_affine, affine_point,
           plane_from_normal_distance, plane_from_points, plane_transform, point_plane_distance,
           segment_plane, barycentric, versor_log, versor_exp)
