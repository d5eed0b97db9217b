"""check_mesh: refuses broken skinned meshes, repairs the two defects real files have."""
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from cgaskin import check_mesh
from cgaskin.errors import InvalidInputError
from cgaskin.tolerances import tol


def quad(joints=None, weights=None):
    """A unit square (4 vertices, 2 faces) with the given influences."""
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    if joints is None:
        joints = np.array([[0, 1, 0, 0]] * 4)
    if weights is None:
        weights = np.array([[0.5, 0.5, 0, 0]] * 4)
    return vertices, faces, np.asarray(joints), np.asarray(weights)


def dense(joints, weights, n_bones):
    """(n, n_bones) weight of each bone at each vertex, duplicates summed."""
    out = np.zeros((len(joints), n_bones))
    np.add.at(out, (np.repeat(np.arange(len(joints)), joints.shape[1]), joints.ravel()), weights.ravel())
    return out


def test_clean_input_passes_unchanged_without_warning():
    v, f, j, w = quad()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        v2, f2, j2, w2 = check_mesh(v, f, j, w, n_bones=2)
    assert v2.dtype == np.float64 and f2.dtype == np.int64 and j2.dtype == np.int64 and w2.dtype == np.float64
    assert np.array_equal(v2, v) and np.array_equal(f2, f) and np.array_equal(j2, j) and np.array_equal(w2, w)


def test_returns_new_arrays_and_leaves_the_callers_alone():
    v, f, j, w = quad(joints=[[0, 1, 2, 3, 4, 5]] * 4, weights=[[0.3, 0.2, 0.2, 0.1, 0.1, 0.3]] * 4)
    copies = [a.copy() for a in (v, f, j, w)]
    with pytest.warns(UserWarning):
        out = check_mesh(v, f, j, w, n_bones=6)
    for original, copy in zip((v, f, j, w), copies):
        assert np.array_equal(original, copy)
    for original, result in zip((v, f, j, w), out):
        assert not np.shares_memory(original, result)
    # and modifying the result does not reach back either
    out[0][0, 0] = 99.0
    assert v[0, 0] == 0.0


def test_weights_not_summing_to_one_are_renormalised_with_a_warning():
    w = np.array([[0.5, 0.4, 0, 0], [0.5, 0.5, 0, 0], [0.6, 0.6, 0, 0], [1.0, 0, 0, 0]])
    v, f, j, _ = quad(weights=w)
    with pytest.warns(UserWarning, match=r"mesh.glb: 2 vertices have weights that do not sum to 1 \(max deviation 0.2 at vertex 2\)"):
        _, _, j2, w2 = check_mesh(v, f, j, w, n_bones=2, source="mesh.glb")
    assert (np.abs(w2.sum(axis=1) - 1) <= tol.exact_weight_sum).all()
    np.testing.assert_allclose(w2[0], [5 / 9, 4 / 9, 0, 0])
    assert np.array_equal(w2[1], w[1]) and np.array_equal(w2[3], w[3])  # rows within tolerance: untouched


def test_float32_noise_is_renormalised_silently():
    """Rows off 1 by less than the tolerance (float32 storage) still end up summing to 1."""
    w = np.array([[0.5, 0.5 - 0.9 * tol.weight_sum, 0, 0]] * 4)
    v, f, j, _ = quad(weights=w)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, _, _, w2 = check_mesh(v, f, j, w)
    np.testing.assert_allclose(w2, w / w.sum(axis=1, keepdims=True), rtol=1e-15)
    assert (np.abs(w2.sum(axis=1) - 1) <= tol.exact_weight_sum).all()


def test_rows_summing_to_one_are_kept_bit_for_bit():
    w = np.array([[0.1, 0.2, 0.3, 0.4]] * 4)  # sums to 1 within an ulp, not exactly
    v, f, j, _ = quad(joints=[[0, 1, 2, 3]] * 4, weights=w)
    _, _, _, w2 = check_mesh(v, f, j, w)
    assert np.array_equal(w2, w)


def test_more_than_four_influences_keep_the_largest_four():
    j = np.array([[0, 1, 2, 3, 4, 5]] * 3 + [[0, 1, 0, 0, 0, 0]])
    w = np.array([[0.05, 0.3, 0.1, 0.25, 0.2, 0.1]] * 3 + [[0.5, 0.5, 0, 0, 0, 0]])
    v, f, _, _ = quad()
    with pytest.warns(UserWarning, match=r"arm.fbx: 3 vertices have more than 4 bone influences \(up to 6\)"):
        _, _, j2, w2 = check_mesh(v, f, j, w, n_bones=6, source="arm.fbx")
    assert j2.shape == (4, 4) and w2.shape == (4, 4)
    # bones 1, 3, 4 and the first of the two 0.1 ties (bone 2, stable order), in slot order
    assert j2[0].tolist() == [1, 2, 3, 4]
    np.testing.assert_allclose(w2[0], np.array([0.3, 0.1, 0.25, 0.2]) / 0.85)
    assert j2[3].tolist() == [0, 1, 0, 0] and w2[3].tolist() == [0.5, 0.5, 0, 0]


def test_duplicate_bones_in_a_row_are_merged_before_counting():
    # 5 slots but only 4 distinct bones: exact merge, no warning
    j = np.array([[2, 1, 2, 3, 0]] * 4)
    w = np.array([[0.1, 0.2, 0.3, 0.25, 0.15]] * 4)
    v, f, _, _ = quad()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, _, j2, w2 = check_mesh(v, f, j, w, n_bones=4)
    assert j2[0].tolist() == [2, 1, 3, 0]
    np.testing.assert_allclose(w2[0], [0.4, 0.2, 0.25, 0.15])


def test_fewer_than_four_slots_are_padded_with_bone_zero_weight_zero():
    v, f, _, _ = quad()
    _, _, j2, w2 = check_mesh(v, f, np.array([[1]] * 4), np.array([[1.0]] * 4), n_bones=2)
    assert j2.tolist() == [[1, 0, 0, 0]] * 4 and w2.tolist() == [[1.0, 0, 0, 0]] * 4


def test_unused_slots_may_hold_any_joint_index():
    j = np.array([[0, 1, 77, -3]] * 4)  # 77 and -3 carry weight 0: ignored, reset to 0
    v, f, _, w = quad()
    _, _, j2, _ = check_mesh(v, f, j, w, n_bones=2)
    assert j2.tolist() == [[0, 1, 0, 0]] * 4


@pytest.mark.parametrize("bad, message", [
    (np.nan, r"vertex 2 has non-finite weights"),
    (np.inf, r"vertex 2 has non-finite weights"),
    (-0.25, r"vertex 2 has negative weights"),
])
def test_bad_weight_values_are_refused(bad, message):
    v, f, j, w = quad()
    w = w.copy()
    w[2, 1] = bad
    with pytest.raises(InvalidInputError, match=message):
        check_mesh(v, f, j, w, n_bones=2)


def test_vertex_without_weight_is_refused():
    v, f, j, w = quad()
    w = w.copy()
    w[3] = 0
    with pytest.raises(InvalidInputError, match=r"vertex 3 has no weight at all \(1 such vertices\)"):
        check_mesh(v, f, j, w)


def test_joint_index_must_be_below_n_bones():
    v, f, _, w = quad()
    with pytest.raises(InvalidInputError, match=r"vertex 0 is weighted to bone indices \[0, 5\], which must be \[0, 3\)"):
        check_mesh(v, f, np.array([[0, 5, 0, 0]] * 4), w, n_bones=3)
    with pytest.raises(InvalidInputError, match=r"which must be >= 0"):
        check_mesh(v, f, np.array([[0, -1, 0, 0]] * 4), w)


def test_non_finite_vertex_and_bad_face_are_refused():
    v, f, j, w = quad()
    v = v.copy()
    v[1, 2] = np.nan
    with pytest.raises(InvalidInputError, match=r"vertex 1 has a non-finite position"):
        check_mesh(v, f, j, w)
    v, f, j, w = quad()
    with pytest.raises(InvalidInputError, match=r"face 1 = \[0, 2, 4\] refers to a vertex outside \[0, 4\)"):
        check_mesh(v, np.array([[0, 1, 2], [0, 2, 4]]), j, w)


@pytest.mark.parametrize("change, message", [
    (lambda v, f, j, w: (v[:, :2], f, j, w), r"vertices must have shape \(n, 3\)"),
    (lambda v, f, j, w: (v, f[:, :2], j, w), r"faces must have shape \(m, 3\)"),
    (lambda v, f, j, w: (v, f.astype(float), j, w), r"faces must hold integer"),
    (lambda v, f, j, w: (v, f, j[:3], w), r"joints must have the shape of weights"),
    (lambda v, f, j, w: (v, f, j, w[:3]), r"weights must have shape \(4, k\)"),
    (lambda v, f, j, w: (v, f, j.astype(float), w), r"joints must hold integer"),
])
def test_wrong_shapes_and_dtypes_are_refused(change, message):
    with pytest.raises(InvalidInputError, match=message):
        check_mesh(*change(*quad()))


def test_output_passes_again_unchanged():
    """Idempotence: what save -> load round trips rely on."""
    rng = np.random.default_rng(0)
    v, f, _, _ = quad()
    j = rng.integers(0, 9, size=(4, 7))
    w = rng.random((4, 7))
    with pytest.warns(UserWarning):
        once = check_mesh(v, f, j, w, n_bones=9)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        twice = check_mesh(*once, n_bones=9)
    for a, b in zip(once, twice):
        assert np.array_equal(a, b)


influences = st.integers(1, 8).flatmap(lambda k: st.tuples(
    hnp.arrays(np.int64, (5, k), elements=st.integers(0, 5)),
    hnp.arrays(np.float64, (5, k), elements=st.one_of(st.just(0.0), st.floats(1e-3, 10.0)))))


@given(influences)
def test_property_per_bone_weights_are_kept_up_to_scale(data):
    """At most 4 bones per vertex, each keeping its (merged) weight, rows summing to 1."""
    joints, weights = data
    weights[:, 0] += 0.5  # every vertex needs some weight
    vertices = np.zeros((5, 3))
    faces = np.zeros((0, 3), dtype=np.int64)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, j2, w2 = check_mesh(vertices, faces, joints, weights, n_bones=6)
    assert j2.shape == w2.shape == (5, 4)
    assert np.all(w2 >= 0) and np.all((w2 > 0).sum(axis=1) <= 4)
    np.testing.assert_allclose(w2.sum(axis=1), 1.0, rtol=0, atol=tol.exact_weight_sum)
    before, after = dense(joints, weights, 6), dense(j2, w2, 6)
    for row in range(5):
        kept = after[row] > 0
        # kept bones are the heaviest ones, in proportion to their original weights
        assert before[row][~kept].max(initial=0) <= before[row][kept].min()
        np.testing.assert_allclose(after[row][kept], before[row][kept] / before[row][kept].sum(), rtol=1e-14)
        if (before[row] > 0).sum() <= 4:
            assert kept.sum() == (before[row] > 0).sum()
