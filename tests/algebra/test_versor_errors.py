"""The versor API's errors: bad input raises InvalidInputError naming the argument (never a numba
traceback), true versors and their products are accepted, and caller arrays are left alone."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, strategies as st

from tests.helpers import strategies as S
from cgaskin import versor as V
from cgaskin.errors import CgaskinError, InvalidInputError
from tests.helpers.tolerances import TOL, matrix_scale, rel_err


# ==== errors =================================================================================================
def _raises(match, fn, *args, **kw):
    with pytest.raises(InvalidInputError, match=match) as info:
        fn(*args, **kw)
    assert isinstance(info.value, ValueError) and isinstance(info.value, CgaskinError)
    return info.value


I12 = V.identity()
BAD_SHAPES = [
    ("translation", V.translator, ([1.0, 2.0],)),
    ("translation", V.translator, (np.zeros((3, 2)),)),
    ("axis", V.rotor, ([0.0, 1.0], 1.0)),
    ("quaternion", V.rotor_from_quaternion, ([0.0, 0.0, 1.0],)),
    ("versor", V.apply, (np.ones(11), [0.0, 0.0, 0.0])),
    ("points", V.apply, (I12, [1.0, 2.0])),
    ("points", V.apply, (I12, "abc")),
    ("points.*real", V.apply, (I12, [[1.0 + 1j, 2.0, 3.0]])),
    ("translation.*real", V.translator, (np.array([1.0, 2.0, 3.0], complex),)),
    ("points", V.apply, (I12, [[1.0, 2.0, 3.0], [1.0, 2.0]])),
    ("versors\\[1\\]", V.compose, (I12, np.ones(11))),
    ("versor", V.inverse, (np.ones(13),)),
    ("versor", V.to_matrix, (np.ones(4),)),
    ("versor", V.log, (np.ones(8),)),
    ("bivector", V.exp, (np.ones(6),)),
    ("matrix", V.from_matrix, (np.eye(3),)),
    ("matrix", V.from_matrix, (np.eye(4)[:3],)),
    ("matrix", V.from_matrix, (np.eye(4)[:, :3],)),
    ("weights", V.blend_linear, (np.stack([I12, I12]), [1.0])),
    ("weights", V.blend_log, (np.stack([I12, I12]), np.ones((2, 2)))),
]


@pytest.mark.parametrize("name, fn, args", BAD_SHAPES,
                         ids=[f"{f.__name__}-{i}" for i, (_, f, _) in enumerate(BAD_SHAPES)])
def test_wrong_shapes_raise(name, fn, args):
    _raises(name, fn, *args)


# Regression (fixed in b5db720): non-broadcasting leading axes used to raise numpy's bare ValueError.
@pytest.mark.parametrize("call", ["rotor", "compose", "apply"])
def test_non_broadcasting_shapes_raise_invalid_input(call):
    with pytest.raises(InvalidInputError):
        if call == "rotor":
            V.rotor(np.ones((4, 3)), np.ones(3))
        elif call == "compose":
            V.compose(V.identity(3), V.identity(2))
        else:
            V.apply(V.identity(3), np.ones((2, 3)))


NON_FINITE = [
    ("translation", lambda bad: V.translator([1.0, bad, 0.0])),
    ("axis", lambda bad: V.rotor([bad, 0.0, 1.0], 1.0)),
    ("angle", lambda bad: V.rotor([0.0, 0.0, 1.0], bad)),
    ("quaternion", lambda bad: V.rotor_from_quaternion([0.0, bad, 0.0, 1.0])),
    ("scale", lambda bad: V.dilator(bad)),
    ("points", lambda bad: V.apply(I12, [0.0, bad, 0.0])),
    ("versor", lambda bad: V.apply(np.r_[bad, np.zeros(11)], [0.0, 0.0, 0.0])),
    ("versors", lambda bad: V.compose(I12, np.r_[1.0, bad, np.zeros(10)])),
    ("versor", lambda bad: V.inverse(np.r_[1.0, np.zeros(10), bad])),
    ("versor", lambda bad: V.to_matrix(np.r_[1.0, np.zeros(10), bad])),
    ("versor", lambda bad: V.normalise(np.r_[1.0, np.zeros(10), bad])),
    ("versor", lambda bad: V.log(np.r_[1.0, np.zeros(10), bad])),
    ("bivector", lambda bad: V.exp(np.r_[np.zeros(6), bad])),
    ("matrix", lambda bad: V.from_matrix(np.where(np.eye(4) > 0, bad, 0.0))),
    ("versors", lambda bad: V.blend_linear(np.stack([I12, np.r_[bad, np.zeros(11)]]), [0.5, 0.5])),
    ("weights", lambda bad: V.blend_log(np.stack([I12, I12]), [bad, 0.5])),
]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("name, make", NON_FINITE, ids=[f"{n}-{i}" for i, (n, _) in enumerate(NON_FINITE)])
def test_non_finite_inputs_raise(name, make, bad):
    _raises(name, make, bad)


@pytest.mark.parametrize("axis", [[0.0, 0.0, 0.0], np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])])
def test_zero_length_axis_raises(axis):
    _raises("axis", V.rotor, axis, 1.0)
    _raises("axis", V.motor, axis, 1.0)


@pytest.mark.parametrize("scale", [0.0, -1.0, -0.0, [1.0, 2.0, 0.0], [-3.0]])
def test_non_positive_scale_raises(scale):
    _raises("scale", V.dilator, scale)


def test_zero_quaternion_raises():
    _raises("quaternion", V.rotor_from_quaternion, [0.0, 0.0, 0.0, 0.0])


@given(S.non_versors())
def test_non_versors_are_rejected(v):
    assert not V.is_versor(v)
    for fn in (V.apply, V.inverse, V.to_matrix, V.to_affine, V.log):
        args = (v, [1.0, 2.0, 3.0]) if fn is V.apply else (v,)
        _raises("versor", fn, *args)
    _raises("versor", V.blend_linear, np.stack([I12, v]), [0.5, 0.5])
    batch = np.stack([I12, v, I12])                      # one bad row in a batch is enough
    _raises("versor", V.apply, batch, [1.0, 2.0, 3.0])


@given(st.lists(S.versors(), min_size=1, max_size=3))
def test_versors_are_accepted(sims):
    """Everything the strategies build (translations to 1e4, scales 0.01..100), and products of it."""
    vs = [s.versor() for s in sims]
    chain = V.compose(*vs)
    assert V.is_versor(np.stack(vs)).all() and V.is_versor(chain)
    V.apply(chain, [1.0, 2.0, 3.0])
    V.to_matrix(V.inverse(chain))


# Regression (fixed in b5db720): the versor check used to ignore the coefficients' size, so this
# product of in-range versors (residual 6.1e-5 from rounding alone) was rejected.
def test_products_of_valid_versors_are_accepted():
    v = V.compose(V.translator([1e4, -1e4, 1e4]), V.rotor([1.0, 2.0, 3.0], 1.0), V.dilator(0.01))
    chain = V.compose(v, v, v, v)
    m = V.to_matrix(v)
    expected = m @ m @ m @ m
    got = V.to_matrix(chain)
    assert rel_err(got, expected, matrix_scale(m, m, m, m)) <= TOL.scale_bound(0.01, 0.01, 0.01, 0.01)


def _non_similarities():
    rot = S.rotation_matrix([1.0, 2.0, 3.0], 0.7)
    out = {}
    m = np.eye(4); m[0, 1] = 0.3; out["shear"] = m
    m = np.eye(4); m[:3, :3] = np.diag([1.0, 1.2, 1.0]) @ rot; out["non-uniform"] = m
    m = np.eye(4); m[:3, :3] = -2.0 * rot; out["reflection (-s R)"] = m
    m = np.eye(4); m[:3, :3] = rot @ np.diag([1.0, 1.0, -1.0]); out["mirror"] = m
    m = np.eye(4); m[3, 0] = 0.1; out["projective row"] = m
    out["zero"] = np.zeros((4, 4))
    m = np.eye(4); m[2, 2] = 0.0; out["singular"] = m
    m = np.eye(4); m[:3, :3] = 1e-3 * np.diag([1.0, 1.0, 1.1]); out["tiny non-uniform"] = m
    return out


@pytest.mark.parametrize("kind", list(_non_similarities()))
def test_from_matrix_rejects_non_similarities(kind):
    _raises("matrix", V.from_matrix, _non_similarities()[kind])


@given(S.versors(), st.sampled_from(["shear", "stretch", "mirror"]), S.log_uniform(1e-3, 0.5), st.integers(0, 2))
def test_from_matrix_rejects_distorted_similarities(sim, kind, amount, axis):
    d = np.eye(4)
    if kind == "shear":
        d[axis, (axis + 1) % 3] = amount
    elif kind == "stretch":
        d[axis, axis] = 1.0 + amount
    else:
        d[axis, axis] = -1.0
    _raises("matrix", V.from_matrix, sim.matrix() @ d)
    _raises("matrix", V.from_matrix, np.stack([sim.matrix(), sim.matrix() @ d]))


def test_errors_are_not_numba_errors():
    """Inputs of the wrong kind are caught before any kernel: no numba TypingError surfaces."""
    for fn, args in ((V.apply, (I12, None)), (V.apply, (I12, [object(), 1, 2])), (V.translator, ({"x": 1},)),
                     (V.apply, ("versor", [0, 0, 0])), (V.exp, (None,)), (V.from_matrix, ("eye",))):
        with pytest.raises(InvalidInputError):
            fn(*args)


# ==== caller arrays are left alone ===========================================================================
def test_inputs_are_not_modified():
    rng = np.random.default_rng(9)
    vs = V.compose(V.translator(rng.uniform(-5, 5, (4, 3))), V.rotor(rng.normal(size=(4, 3)), rng.uniform(-3, 3, 4)),
                   V.dilator(rng.uniform(0.5, 2, 4)))
    arrays = {
        "vs": vs, "neg": -vs, "x": rng.uniform(-5, 5, (4, 3)), "t": rng.uniform(-5, 5, (4, 3)),
        "axis": rng.normal(size=(4, 3)), "angle": rng.uniform(-3, 3, 4), "scale": rng.uniform(0.5, 2, 4),
        "q": rng.normal(size=(4, 4)), "m": V.to_matrix(vs), "w": np.array([[0.3, 0.7]] * 4),
        "L": V.log(vs), "blend": 0.5 * vs,
    }
    before = {k: v.copy() for k, v in arrays.items()}
    pairs = np.stack([arrays["vs"], arrays["neg"]], axis=1)
    pairs_before = pairs.copy()
    a = arrays
    V.translator(a["t"]); V.rotor(a["axis"], a["angle"]); V.dilator(a["scale"]); V.rotor_from_quaternion(a["q"])
    V.compose(a["vs"], a["neg"]); V.reverse(a["vs"]); V.inverse(a["vs"]); V.normalise(a["blend"])
    V.apply(a["vs"], a["x"]); V.to_matrix(a["vs"]); V.to_affine(a["vs"]); V.from_matrix(a["m"])
    V.log(a["vs"]); V.exp(a["L"]); V.blend_linear(pairs, a["w"]); V.blend_log(pairs, a["w"])
    V.is_versor(a["vs"]); V.to_clifford(a["vs"][0])
    for k in arrays:
        np.testing.assert_array_equal(arrays[k], before[k], err_msg=f"{k} was modified")
    np.testing.assert_array_equal(pairs, pairs_before, err_msg="blend input was modified")


# Regression (fixed in b5db720): compose(v) used to hand back the caller's array.
def test_outputs_do_not_alias_inputs():
    v = V.identity()
    out = V.compose(v)
    out[0] = 7.0
    assert v[0] == 1.0, "compose of one versor handed back the caller's array"
    assert not np.shares_memory(V.compose(v), v)


def test_other_outputs_are_fresh_arrays():
    v = V.compose(V.translator([1.0, 2.0, 3.0]), V.rotor([0.0, 0.0, 1.0], 0.5))
    x = np.array([1.0, 2.0, 3.0])
    for out in (V.compose(v, V.identity()), V.reverse(v), V.inverse(v), V.normalise(v), V.apply(v, x),
                V.to_affine(v), V.to_matrix(v), V.exp(V.log(v))):
        assert not np.shares_memory(out, v) and not np.shares_memory(out, x)


@pytest.mark.parametrize("column, value", [(6, 800.0), (6, -800.0), (3, 1e308)])
def test_exp_that_overflows_raises(column, value):
    bivector = np.zeros((2, 7))
    bivector[1, column] = value
    _raises("overflows", V.exp, bivector)
    np.testing.assert_array_equal(V.exp(bivector[:1]), V.identity()[None])
