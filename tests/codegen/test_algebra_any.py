"""``codegen.Algebra``: G(p, q, r) up to 6 dimensions, orthonormal or null basis, against clifford.

The oracle is ``clifford.Cl(p, q, r)`` (vectors: r degenerate, p positive, q negative, in that order,
clifford's e1 ... en). Our vector k is clifford's e(k+1) in an orthonormal basis; in a null basis the
last positive e+ and the last negative e− of clifford become e∞ = e− + e+, eo = (e− − e+)/2, put last.
Each of our blades (outer product of its vectors) is turned into clifford coordinates; then for every
pair of blades and every product kind, clifford's product of the two images (from its own product
tensors gmt / omt / lcmt) must equal the image of our table entry. Reverse and grade involution go
through clifford's operators (~x, x.even − x.odd); random multivectors through clifford's MultiVector products.
``cga`` reproduces the tables of the module-level ``codegen.algebra`` exactly (a digest frozen before
the generalisation, and known entries).
"""
from __future__ import annotations

import hashlib
from fractions import Fraction
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cgaskin.codegen import Algebra, InvalidAlgebraError, algebra, cga, pga
from cgaskin.codegen.algebras import KINDS
from cgaskin.errors import InvalidInputError

from tests.helpers.tolerances import TOL

CASES = [((3, 0, 0), "orthonormal"), ((2, 0, 0), "orthonormal"), ((1, 1, 0), "orthonormal"),
         ((3, 1, 0), "orthonormal"), ((4, 1, 0), "orthonormal"), ((2, 2, 0), "orthonormal"),
         ((3, 0, 1), "orthonormal"), ((4, 1, 0), "null"), ((5, 1, 0), "orthonormal"), ((5, 1, 0), "null"),
         ((2, 0, 1), "orthonormal"), ((2, 2, 0), "null"), ((1, 1, 1), "null")]
IDS = [f"G{p}{q}{r}-{basis}" for (p, q, r), basis in CASES]
TENSOR = {"gp": "gmt", "outer": "omt", "lcontract": "lcmt"}


@lru_cache(maxsize=None)
def _oracle(signature, basis):
    """(our algebra, clifford layout, B): column m of B is our blade m in clifford coordinates."""
    import clifford
    p, q, r = signature
    alg = Algebra(signature=signature, basis=basis)
    layout, blades = clifford.Cl(p, q, r)
    n = p + q + r
    assert tuple(layout.sig) == (0,) * r + (1,) * p + (-1,) * q
    cv = [blades[f"e{k + 1}"].value for k in range(n)]
    if basis == "null":
        ep, em = cv[r + p - 1], cv[n - 1]
        cv = [v for k, v in enumerate(cv) if k not in (r + p - 1, n - 1)] + [em + ep, 0.5 * (em - ep)]
    omt = layout.omt.todense()
    B = np.zeros((layout.gaDims, alg.n_blades))
    for m in range(alg.n_blades):
        x = layout.scalar.value.copy()
        for k in alg.vectors_of(m):
            x = np.einsum("i,ikj,j->k", x, omt, cv[k])
        B[:, m] = x
    return alg, layout, B


def _table_array(alg, kind):
    n = alg.n_blades
    C = np.zeros((n, n, n))                          # C[m, a, b]: coefficient of blade m in a ∘ b
    for (a, b), entry in alg.product_table(kind).items():
        for m, c in entry:
            C[m, a, b] = float(c)
    return C


@pytest.mark.parametrize("signature, basis", CASES, ids=IDS)
def test_every_blade_pair_matches_clifford(signature, basis):
    alg, layout, B = _oracle(signature, basis)
    assert np.linalg.matrix_rank(B) == alg.n_blades        # our blades are a basis
    for kind in KINDS:
        T = getattr(layout, TENSOR[kind]).todense()
        got = np.einsum("ia,ikj,jb->kab", B, T, B, optimize=True)   # clifford: image(a) ∘ image(b)
        expected = np.einsum("km,mab->kab", B, _table_array(alg, kind))
        bad = np.argwhere(np.abs(got - expected).max(axis=0) > TOL.table)
        names = [(alg.blade_display(a), alg.blade_display(b)) for a, b in bad[:5]]
        assert not len(bad), f"{alg} {kind}: {len(bad)} blade pairs differ from clifford, e.g. {names}"


@pytest.mark.parametrize("signature, basis", CASES, ids=IDS)
def test_reverse_and_involution_match_clifford(signature, basis):
    alg, layout, B = _oracle(signature, basis)
    c = np.arange(1.0, alg.n_blades + 1)                    # distinct coefficients; B is a basis
    x = layout.MultiVector(B @ c)
    np.testing.assert_allclose((~x).value, B @ (c * [alg.reverse_sign(m) for m in range(alg.n_blades)]),
                               rtol=0, atol=TOL.table * alg.n_blades ** 2)
    np.testing.assert_allclose((x.even - x.odd).value,          # grade involution
                               B @ (c * [alg.involution_sign(m) for m in range(alg.n_blades)]),
                               rtol=0, atol=TOL.table * alg.n_blades ** 2)


@pytest.mark.parametrize("signature, basis", CASES, ids=IDS)
def test_metric_is_the_vectors_inner_products(signature, basis):
    alg, layout, B = _oracle(signature, basis)
    p, q, r = signature
    V = B[:, [1 << k for k in range(alg.dimension)]]       # our vectors in clifford coordinates
    gmt = layout.gmt.todense()
    gram = np.einsum("ia,ij,jb->ab", V, gmt[:, 0, :], V)   # scalar part of a b (= a·b for vectors)
    np.testing.assert_array_equal(gram, np.array(alg.metric, dtype=float))
    assert sorted(alg.orthonormal_metric) == sorted((0,) * r + (1,) * p + (-1,) * q)
    assert alg.pseudoscalar == alg.n_blades - 1 and len(alg.blades) == alg.n_blades == 1 << (p + q + r)


# ---- random multivectors through clifford's own MultiVector products (one JIT per layout: two layouts) ----
RANDOM_CASES = [((3, 0, 1), "orthonormal"), ((5, 1, 0), "null")]
rationals = st.fractions(min_value=-8, max_value=8, max_denominator=8)


def _product(alg, x, y, kind):
    out: dict[int, Fraction] = {}
    table = alg.product_table(kind)
    for a, ca in x.items():
        for b, cb in y.items():
            for m, c in table[a, b]:
                out[m] = out.get(m, 0) + ca * cb * c
    return out


def _to_clifford(layout, B, x):
    return layout.MultiVector(sum((float(c) * B[:, m] for m, c in x.items()), np.zeros(layout.gaDims)))


@pytest.mark.parametrize("signature, basis", RANDOM_CASES, ids=["pga", "G510-null"])
@settings(max_examples=5, deadline=None)
@given(data=st.data())
def test_random_multivector_products_match_clifford(signature, basis, data):
    alg, layout, B = _oracle(signature, basis)
    coefficients = st.dictionaries(st.integers(0, alg.n_blades - 1), rationals, max_size=10)
    x, y = data.draw(coefficients), data.draw(coefficients)
    cx, cy = _to_clifford(layout, B, x), _to_clifford(layout, B, y)
    for kind, expected in (("gp", cx * cy), ("outer", cx ^ cy), ("lcontract", cx << cy)):
        got = _to_clifford(layout, B, _product(alg, x, y, kind)).value
        scale = max(1.0, float(np.max(np.abs(expected.value))))
        assert float(np.max(np.abs(got - expected.value))) <= TOL.table * 64 * scale, f"{alg} {kind}"


# ---- cga is the codegen.algebra of before; pga's convention -----------------------------------------------
# sha256 of repr([sorted(product_table(k).items()) for k in ('gp', 'outer', 'lcontract')]) of the
# module-level tables of codegen/algebra.py before Algebra existed (commit 70fc327)
CGA_TABLES_DIGEST = "38e4978429bbad18b23e9fc8c460e1a72f798663dd42fc94ff7005d45895eef0"


def test_cga_reproduces_the_previous_tables_exactly():
    fresh = Algebra(signature=(4, 1, 0), basis="null")
    assert fresh == cga and fresh is not cga
    tables = [sorted(fresh.product_table(k).items()) for k in KINDS]
    assert hashlib.sha256(repr(tables).encode()).hexdigest() == CGA_TABLES_DIGEST
    for kind in KINDS:
        assert algebra.product_table(kind) == fresh.product_table(kind)
    assert (algebra.DIMENSION, algebra.N_BLADES, algebra.PSEUDOSCALAR) == (5, 32, 31)
    assert algebra.VECTOR_NAMES == ("1", "2", "3", "i", "o") and algebra.DISPLAY_NAMES == ("1", "2", "3", "∞", "0")
    assert algebra.ORTHONORMAL_METRIC == (1, 1, 1, 1, -1)
    gp, i, o, io = cga.product_table("gp"), cga.mask_of("ei"), cga.mask_of("eo"), cga.mask_of("e∞0")
    assert (i, o, io) == (8, 16, 24)
    assert dict(gp[i, o]) == {0: -1, io: 1} and dict(gp[o, i]) == {0: -1, io: -1}   # e∞e0 = −1 + e∞∧e0
    assert gp[i, i] == () == gp[o, o] and dict(gp[io, io]) == {0: 1}
    assert cga.metric[3][4] == cga.metric[4][3] == -1 and cga.metric[3][3] == cga.metric[4][4] == 0
    for m in range(32):
        assert algebra.blade_name(m) == cga.blade_name(m) and algebra.reverse_sign(m) == cga.reverse_sign(m)
        assert algebra.mask_of(cga.blade_name(m)) == m == algebra.mask_of(cga.blade_display(m))


def test_pga_puts_the_degenerate_e0_first_and_maps_to_clifford_by_name():
    import clifford
    assert pga.vector_names == ("0", "1", "2", "3") and pga.orthonormal_metric == (0, 1, 1, 1)
    gp, lc = pga.product_table("gp"), pga.product_table("lcontract")
    e0, e1, e01 = pga.mask_of("e0"), pga.mask_of("e1"), pga.mask_of("e01")
    assert gp[e0, e0] == () and lc[e0, e0] == () and dict(gp[e1, e1]) == {0: 1}
    assert dict(gp[e0, e1]) == {e01: 1} and dict(gp[e01, e01]) == {}                 # e01² = 0
    layout, blades = clifford.Cl(3, 0, 1)
    _, _, B = _oracle((3, 0, 1), "orthonormal")
    for m in range(1, pga.n_blades):                      # our e0123 is clifford's e1234, and so on
        name = "e" + "".join(str(int(ch) + 1) for ch in pga.blade_name(m)[1:])
        np.testing.assert_array_equal(B[:, m], blades[name].value)


def test_names_and_display_override():
    sta = Algebra(signature=(1, 3, 0), names="0123", display="txyz")
    assert sta.blade_name(0b1001) == "e03" and sta.blade_display(0b1001) == "etz"
    assert sta.mask_of("etz") == sta.mask_of("e03") == 0b1001
    assert Algebra((2, 0, 0)).vector_names == ("1", "2")
    assert Algebra((2, 0, 1), "orthonormal").vector_names == ("0", "1", "2")
    assert Algebra((2, 1, 1), "null").vector_names == ("1", "2", "i", "o")


# ---- bad arguments ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, argument", [
    (dict(signature=(4, 2, 1)), "signature="),                      # dimension 7
    (dict(signature=(7, 0, 0)), "signature="),
    (dict(signature=(0, 0, 0)), "signature="),
    (dict(signature=(-1, 1, 0)), "signature="),
    (dict(signature=(3, 1)), "signature="),
    (dict(signature=(3.0, 1, 0)), "signature="),
    (dict(signature=(3, 0, 0), basis="null"), "basis='null'"),       # no e− to pair with e+
    (dict(signature=(0, 2, 1), basis="null"), "basis='null'"),
    (dict(signature=(4, 1, 0), basis="conformal"), "basis="),
    (dict(signature=(3, 0, 0), names=("x", "y")), "names="),
    (dict(signature=(3, 0, 0), names=("x", "x", "z")), "names="),
    (dict(signature=(3, 0, 0), names=("x", "yy", "z")), "names="),
    (dict(signature=(2, 0, 0), names="xy", display="yx"), "display="),
])
def test_bad_arguments_raise_naming_the_argument(kwargs, argument):
    with pytest.raises(InvalidAlgebraError, match=argument.replace("(", r"\(")) as info:
        Algebra(**kwargs)
    assert isinstance(info.value, InvalidInputError) and isinstance(info.value, ValueError)


def test_bad_kind_and_blade_name():
    with pytest.raises(InvalidAlgebraError, match="kind="):
        pga.product_table("inner")
    for name in ("ex", "e11", "x1", ""):
        with pytest.raises(InvalidAlgebraError, match="blade name"):
            pga.mask_of(name)
