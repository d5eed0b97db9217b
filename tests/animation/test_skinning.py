"""skin_vertices / skin_affine against a plain matrix LBS, and their input checks."""
import numpy as np
import pytest
from hypothesis import given, strategies as st

import cgaskin
from cgaskin import versor
from cgaskin.baselines import lbs_matrices
from cgaskin.errors import InvalidInputError


def random_skin(seed, n=200, n_bones=6, k=4, coordinate=10.0):
    rng = np.random.default_rng(seed)
    rest = rng.uniform(-coordinate, coordinate, (n, 3))
    joints = rng.integers(0, n_bones, (n, k))
    weights = rng.random((n, k))
    weights /= weights.sum(1, keepdims=True)
    axis = rng.normal(size=(n_bones, 3))
    angle = rng.uniform(-np.pi, np.pi, n_bones)
    angle[0] = np.pi                                   # exactly π is a case of its own for rotors
    v = versor.compose(versor.motor(axis, angle, rng.uniform(-coordinate, coordinate, (n_bones, 3))),
                       versor.dilator(np.exp(rng.uniform(np.log(0.01), np.log(100), n_bones))))
    return rest, joints, weights, v


@given(st.integers(0, 2**32 - 1), st.sampled_from([1.0, 1e2, 1e4]))
def test_equals_matrix_lbs(seed, coordinate):
    rest, joints, weights, v = random_skin(seed, coordinate=coordinate)
    expected = lbs_matrices(rest, joints, weights, versor.to_matrix(v))
    scale = np.abs(expected).max()
    for parallel in (False, True):
        got = cgaskin.skin_vertices(rest, joints, weights, v, parallel=parallel)
        assert np.abs(got - expected).max() <= 1e-12 * scale


def test_compact_dtypes_and_out():
    rest, joints, weights, v = random_skin(1)
    expected = cgaskin.skin_vertices(rest, joints, weights, v)
    out = np.empty_like(rest)
    got = cgaskin.skin_vertices(rest, joints.astype(np.uint8), weights.astype(np.float32), v, out=out)
    assert got is out
    assert np.allclose(got, expected, rtol=0, atol=1e-5 * np.abs(expected).max())


def test_does_not_modify_inputs():
    rest, joints, weights, v = random_skin(2)
    copies = [a.copy() for a in (rest, joints, weights, v)]
    cgaskin.skin_vertices(rest, joints, weights, v)
    for a, c in zip((rest, joints, weights, v), copies):
        assert np.array_equal(a, c)


@pytest.mark.parametrize("parallel", [False, True])
def test_bad_input(parallel):
    rest, joints, weights, v = random_skin(3)
    bad_joints = joints.copy()
    bad_joints[17, 2] = 99
    with pytest.raises(InvalidInputError, match="joints"):
        cgaskin.skin_vertices(rest, bad_joints, weights, v, parallel=parallel)
    bad_joints[17, 2] = -1
    with pytest.raises(InvalidInputError, match="joints"):
        cgaskin.skin_vertices(rest, bad_joints, weights, v, parallel=parallel)
    for name, arr in (("rest", rest), ("weights", weights)):
        nan = arr.copy()
        nan[5, 1] = np.nan
        args = dict(rest=rest, joints=joints, weights=weights, versors=v, parallel=parallel)
        args[name] = nan
        with pytest.raises(InvalidInputError, match=name):
            cgaskin.skin_vertices(**args)
    with pytest.raises(InvalidInputError, match="rest"):
        cgaskin.skin_vertices(rest[:, :2], joints, weights, v)
    with pytest.raises(InvalidInputError, match="joints shape"):
        cgaskin.skin_vertices(rest, joints[:, :3], weights, v)
    with pytest.raises(InvalidInputError, match="not a similarity versor"):
        cgaskin.skin_vertices(rest, joints, weights, v + 0.5)


def test_nan_affine_is_named():
    rest, joints, weights, v = random_skin(4)
    affines = versor.to_affine(v)
    affines[2, 1, 3] = np.nan
    with pytest.raises(InvalidInputError, match="affines"):
        cgaskin.skin_affine(rest, joints, weights, affines)
