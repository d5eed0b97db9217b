"""The multivector pieces several builder kernel families build from (the array layouts are in ``layouts``).

The conventions these follow are in catalogue.py's docstring (design.md §2).
"""
from __future__ import annotations

import sympy
from sympy import Rational

from .layouts import ROTOR, VERSOR
from .symbolic import MV

HALF = Rational(1, 2)


def euclid(k, mv, blades=("e1", "e2", "e3")):
    """The coefficients of mv on e1, e2, e3 (or on ``blades``)."""
    return [mv[b] for b in blades]


def rotor_from_quaternion(k, q):
    """Rotor w − x e23 + y e13 − z e12 of the quaternion q = (x, y, z, w) (not normalised here)."""
    x, y, z, w = (k.poly(c) for c in q)
    return k.mv(ROTOR, [w, -z, y, -x])


def translator(k, t):
    """Translator T(t) = 1 − ½ t e∞."""
    t1, t2, t3 = (k.poly(c) for c in t)
    return k.mv(("s", "e1i", "e2i", "e3i"), [1, -t1 * HALF, -t2 * HALF, -t3 * HALF])


def dilator(k, cosh_half, sinh_half):
    """Dilator cosh(ln s/2) − sinh(ln s/2) e∞0, from those two values."""
    return k.mv(("s", "eio"), [k.poly(cosh_half), -k.poly(sinh_half)])


def down(k, X: MV):
    """Euclidean point of a conformal point: Euclidean part over the e0 coefficient."""
    w = X["eo"]
    return [sympy.Mul(c.as_expr(), sympy.Pow(w.as_expr(), -1)) for c in euclid(k, X)]


E_PAIRS = (("s", "eio"), ("e12", "e12io"), ("e13", "e13io"), ("e23", "e23io"))


def idempotent_versor(k, v):
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
