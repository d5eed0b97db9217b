"""codegen's product tables and symbolic multivectors against two independent implementations.

The tables (``cgaskin.codegen.algebra.product_table``) are exact fractions over the null basis
e1, e2, e3, e-inf, e0 (e-inf = e- + e+, e0 = (e- - e+)/2, blades = outer products in index order). They are
checked for every pair of the 32 blades:

- against galgebra (exact, sympy rationals) for the geometric, outer and left-contraction products;
- against clifford.Cl(4, 1) (floats) for the same three products.

The symbolic ``MV`` class (reverse, grade, dual, products) is checked on random rational coefficients
against clifford.
"""
from __future__ import annotations

from fractions import Fraction
from functools import lru_cache

import numpy as np
import pytest
import sympy
from hypothesis import given, strategies as st
from sympy import QQ
from sympy.polys.rings import ring

from cgaskin.codegen import algebra
from cgaskin.codegen.symbolic import MV

from tests.helpers.tolerances import TOL

KINDS = ("gp", "outer", "lcontract")
MASKS = range(algebra.N_BLADES)


# ---- galgebra: exact ------------------------------------------------------------------------------------
@lru_cache(maxsize=None)
def _galgebra():
    from galgebra.ga import Ga
    ga, e1, e2, e3, ep, em = Ga.build("e1 e2 e3 e4 e5", g=[1, 1, 1, 1, -1])
    einf = em + ep
    e0 = (em - ep) / 2
    vectors = (e1, e2, e3, einf, e0)
    blades = []
    for mask in MASKS:
        blade = ga.mv(sympy.S(1), "scalar")
        for k in algebra.vectors_of(mask):
            blade = blade ^ vectors[k]
        blades.append(blade)
    return ga, (e1, e2, e3, ep, em), vectors, blades


def _galgebra_product(x, y, kind):
    if kind == "gp":
        return x * y
    if kind == "outer":
        return x ^ y
    return x < y                                 # galgebra: '<' is the left contraction


@pytest.mark.parametrize("kind", KINDS)
def test_tables_match_galgebra_exactly(kind):
    _, _, _, blades = _galgebra()
    coefs = [b.blade_coefs() for b in blades]                     # orthonormal-basis coordinates
    table = algebra.product_table(kind)
    mismatches = []
    for a in MASKS:
        for b in MASKS:
            got = _galgebra_product(blades[a], blades[b], kind).blade_coefs()
            expected = [sympy.S(0)] * len(got)
            for mask, c in table[a, b]:
                rc = sympy.Rational(c.numerator, c.denominator)
                expected = [e + rc * x for e, x in zip(expected, coefs[mask])]
            if any(sympy.simplify(g - e) != 0 for g, e in zip(got, expected)):
                mismatches.append((algebra.blade_display(a), algebra.blade_display(b)))
    assert not mismatches, f"{kind}: {len(mismatches)} blade pairs differ from galgebra, e.g. {mismatches[:5]}"


def test_null_basis_facts_galgebra():
    ga, (e1, e2, e3, ep, em), (_, _, _, einf, e0), blades = _galgebra()
    one = ga.mv(1, "scalar")
    assert einf * einf == 0 * one and e0 * e0 == 0 * one
    assert (einf | e0) == -1 * one and (e0 | einf) == -1 * one
    # the pseudoscalar e123-inf-0 equals e1 e2 e3 e+ e- and squares to -1
    assert blades[algebra.PSEUDOSCALAR] == e1 * e2 * e3 * ep * em
    assert blades[algebra.PSEUDOSCALAR] * blades[algebra.PSEUDOSCALAR] == -1 * one
    # the blade of e-inf^e0 is the outer product, not the geometric product
    eio = algebra.mask_of("eio")
    assert blades[eio] == einf ^ e0 and blades[eio] != einf * e0


def test_table_identities():
    gp = algebra.product_table("gp")
    i, o, io = algebra.mask_of("ei"), algebra.mask_of("eo"), algebra.mask_of("eio")
    assert gp[i, i] == () and gp[o, o] == ()
    # e-inf e0 = e-inf.e0 + e-inf^e0 = -1 + e-inf0
    assert dict(gp[i, o]) == {0: -1, io: 1}
    assert dict(gp[io, io]) == {0: 1}                          # (e-inf^e0)^2 = 1
    for a in MASKS:                                              # scalar is the identity
        assert gp[0, a] == ((a, Fraction(1)),) and gp[a, 0] == ((a, Fraction(1)),)


def test_mask_names_round_trip():
    for m in MASKS:
        assert algebra.mask_of(algebra.blade_name(m)) == m
        assert algebra.mask_of(algebra.blade_display(m)) == m


# ---- clifford: floats -------------------------------------------------------------------------------------
@lru_cache(maxsize=None)
def _clifford():
    from clifford import g3c
    vectors = (g3c.e1, g3c.e2, g3c.e3, g3c.einf, g3c.eo)
    one = g3c.layout.scalar
    blades = []
    for mask in MASKS:
        blade = 1.0 * one
        for k in algebra.vectors_of(mask):
            blade = blade ^ vectors[k]
        blades.append(blade)
    basis = np.stack([b.value for b in blades], axis=1)         # (32 ortho coords, 32 null blades)
    return g3c, blades, basis


def _clifford_mv(coefficients: dict[int, float]):
    g3c, blades, _ = _clifford()
    value = np.zeros(algebra.N_BLADES)
    for m, c in coefficients.items():
        value = value + float(c) * blades[m].value
    return g3c.layout.MultiVector(value)


def _clifford_product(x, y, kind):
    if kind == "gp":
        return x * y
    if kind == "outer":
        return x ^ y
    return x << y                                  # clifford: '<<' is the left contraction


@pytest.mark.parametrize("kind", KINDS)
def test_tables_match_clifford(kind):
    g3c, blades, basis = _clifford()
    table = algebra.product_table(kind)
    worst = 0.0
    for a in MASKS:
        for b in MASKS:
            got = _clifford_product(blades[a], blades[b], kind).value
            expected = sum((float(c) * basis[:, m] for m, c in table[a, b]), np.zeros(algebra.N_BLADES))
            worst = max(worst, float(np.max(np.abs(got - expected))))
    assert worst <= TOL.table, f"{kind}: worst coefficient difference {worst:.3g} against clifford"


def test_clifford_null_vectors_match_design():
    g3c, blades, _ = _clifford()
    ep, em = g3c.e4, g3c.e5
    assert abs((ep * ep)[()] - 1) == 0 and abs((em * em)[()] + 1) == 0
    np.testing.assert_array_equal((em + ep).value, g3c.einf.value)
    np.testing.assert_array_equal((0.5 * (em - ep)).value, g3c.eo.value)
    np.testing.assert_array_equal(blades[algebra.PSEUDOSCALAR].value, (g3c.e1 * g3c.e2 * g3c.e3 * ep * em).value)


# ---- the symbolic MV class on numbers ----------------------------------------------------------------------
_RING, _X = ring("x", QQ)

rationals = st.fractions(min_value=-8, max_value=8, max_denominator=16)
sparse_coefficients = st.dictionaries(st.integers(0, algebra.N_BLADES - 1), rationals, max_size=12)


def _mv(coefficients: dict[int, Fraction]) -> MV:
    return MV(_RING, {m: _RING(QQ(c.numerator, c.denominator)) for m, c in coefficients.items()})


def _numbers(x: MV) -> dict[int, float]:
    out = {}
    for m, c in x.terms.items():
        assert c.is_ground, "numeric MV has a symbol left"
        q = c.LC if c else 0
        out[m] = float(Fraction(int(q.numerator), int(q.denominator)))
    return out


def _assert_same(x: MV, clifford_mv, what: str):
    got = _clifford_mv(_numbers(x)).value
    expected = clifford_mv.value
    scale = max(1.0, float(np.max(np.abs(expected))))
    err = float(np.max(np.abs(got - expected)))
    assert err <= TOL.table * scale, f"{what}: differs from clifford by {err:.3g}"


@given(sparse_coefficients)
def test_mv_reverse_and_grade_match_clifford(coefficients):
    x = _mv(coefficients)
    cx = _clifford_mv(coefficients)
    _assert_same(x.reverse(), ~cx, "reverse")
    for g in range(6):
        _assert_same(x.grade(g), cx(g), f"grade {g}")
    _assert_same(x.grade(0, 2, 4), cx(0) + cx(2) + cx(4), "grades 0, 2, 4")


@given(sparse_coefficients)
def test_mv_dual_matches_clifford(coefficients):
    g3c, blades, _ = _clifford()
    x = _mv(coefficients)
    cx = _clifford_mv(coefficients)
    pseudoscalar = blades[algebra.PSEUDOSCALAR]                  # e1^e2^e3^e-inf^e0
    _assert_same(x.dual(), cx * pseudoscalar.inv(), "dual = X I^-1")
    _assert_same(x.dual(), -(cx * pseudoscalar), "dual = -X I (I^2 = -1)")


@given(sparse_coefficients, sparse_coefficients)
def test_mv_products_match_clifford(ca, cb):
    x, y = _mv(ca), _mv(cb)
    cx, cy = _clifford_mv(ca), _clifford_mv(cb)
    _assert_same(x * y, cx * cy, "geometric product")
    _assert_same(x ^ y, cx ^ cy, "outer product")
    _assert_same(x.lc(y), cx << cy, "left contraction")
    _assert_same(x + y, cx + cy, "sum")
    _assert_same(x - y, cx - cy, "difference")


@given(sparse_coefficients)
def test_mv_products_with_symbols_specialise(coefficients):
    """Products with a symbolic coefficient, evaluated at a number, equal the numeric product."""
    x = _mv(coefficients) + MV(_RING, {algebra.mask_of("e1i"): _X})
    y = _mv(coefficients).reverse() + MV(_RING, {algebra.mask_of("eio"): _X * 3})
    prod = x * y
    at = Fraction(3, 7)
    value = MV(_RING, {m: _RING(c(QQ(at.numerator, at.denominator))) for m, c in prod.terms.items()})
    x_num = dict(coefficients)
    x_num[algebra.mask_of("e1i")] = x_num.get(algebra.mask_of("e1i"), 0) + at
    y_num = _numbers(_mv(coefficients).reverse())
    y_num[algebra.mask_of("eio")] = y_num.get(algebra.mask_of("eio"), 0) + 3 * float(at)
    _assert_same(value, _clifford_mv(x_num) * _clifford_mv(y_num), "specialised symbolic product")
