"""New vertices on edges and in faces (cgaskin.surgery.new_vertices), shared by cut and tear: weights,
attributes and rest placement, against plain numpy."""
import numpy as np
from hypothesis import given, settings, strategies as st

from cgaskin.surgery.new_vertices import (NewVertices, blend_weight_rows, interpolate_attribute, on_edges,
                                          place_in_rest)


def test_rest_placement_solves_the_blended_map():
    rng = np.random.default_rng(3)
    affines = rng.normal(size=(3, 12))
    joints = np.array([[0, 1, 2, 0], [0, 0, 0, 0]])
    weights = np.array([[0.5, 0.3, 0.2, 0.0], [1.0, 0, 0, 0]])
    x = rng.normal(size=(2, 3))
    blend = np.einsum("vk,vkc->vc", weights, affines[joints]).reshape(-1, 3, 4)
    target = np.einsum("vij,vj->vi", blend[:, :, :3], x) + blend[:, :, 3]
    rest, residual = place_in_rest(target, x + 0.1, joints, weights, affines)
    assert np.allclose(rest, x, atol=1e-12) and residual.max() < 1e-13
    # a singular blend (here all zero) keeps the guess and says so with an infinite residual
    rest, residual = place_in_rest(target, x, joints, weights, np.zeros((3, 12)))
    assert np.isinf(residual).all() and np.array_equal(rest, x)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 3))
def test_attributes_interpolate_like_numpy(seed, r):
    rng = np.random.default_rng(seed)
    n, k = 7, 5
    src = rng.integers(0, n, size=(k, r))
    coef = rng.random((k, r))
    coef /= coef.sum(axis=1, keepdims=True)
    new = NewVertices(src, coef)
    uv = rng.normal(size=(n, 2)).astype(np.float32)
    expected = np.einsum("kr,krc->kc", coef, uv[src].astype(np.float64))
    got = interpolate_attribute("TEXCOORD_0", uv, new)
    assert got.dtype == np.float32 and np.allclose(got, expected, atol=1e-6)
    normals = rng.normal(size=(n, 3))
    blended = np.einsum("kr,krc->kc", coef, normals[src])
    got = interpolate_attribute("NORMAL", normals, new)
    assert np.allclose(got, blended / np.linalg.norm(blended, axis=1, keepdims=True), atol=1e-12)
    # application-specific data may not be interpolable (labels): the dominant source's row
    labels = np.arange(n, dtype=np.float64)[:, None] * 10
    got = interpolate_attribute("_LABEL", labels, new)
    assert np.array_equal(got[:, 0], labels[src[np.arange(k), coef.argmax(axis=1)], 0])


def test_edge_points_blend_weights_of_both_ends():
    joints = np.array([[0, 1, 0, 0], [2, 1, 0, 0]])
    weights = np.array([[0.75, 0.25, 0, 0], [0.5, 0.5, 0, 0]])
    new = on_edges(np.array([0]), np.array([1]), np.array([0.5]))
    assert np.array_equal(new.coef, [[0.5, 0.5]])
    j, w = blend_weight_rows(new.src, new.coef, joints, weights)
    assert np.allclose(w.sum(axis=1), 1.0)
    got = {b: x for b, x in zip(j[0].tolist(), w[0].tolist()) if x > 0}   # unused slots: bone 0, weight 0
    assert np.isclose(got[0], 0.375) and np.isclose(got[1], 0.375) and np.isclose(got[2], 0.25)
    assert list(w[0]) == sorted(w[0], reverse=True)
