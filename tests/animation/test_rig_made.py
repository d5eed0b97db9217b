"""Rigs that cannot lie (issue 22, items 1-3): a ``Rig`` is checked where it is made (constructor,
``with_mesh``, ``dataclasses.replace``) by the same ``check_mesh`` that loaders and ``save`` use, and
its arrays are read-only, so that no edit can leave its caches (BVH, welded topology) stale."""
import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import cgaskin
from cgaskin import InvalidInputError, Rig, Skeleton

# a blade across the Fox's back (the precompile workload's), two strokes
FOX_STROKES = (([0.0, 120, 0], [0.0, 40, 0]), ([0.0, 120, 10], [0.0, 40, 10]))


@pytest.fixture(scope="module")
def fox(models_dir):
    return cgaskin.load(models_dir / "Fox.glb")


def _mesh(rig):
    """The rig's mesh as new writeable arrays (what a caller hands to ``with_mesh``)."""
    return [np.array(a) for a in (rig.vertices, rig.faces, rig.joints, rig.weights)]


# ---- item 1: rows without weight ------------------------------------------------------------------------
def test_all_zero_weights_are_refused_by_with_mesh_like_save(fox, tmp_path):
    v, f, j, w = _mesh(fox)
    with pytest.raises(InvalidInputError, match=r"vertex 0 has no weight at all \(1728 such vertices\).*root bone"):
        fox.with_mesh(v, f, j, np.zeros_like(w))


@given(row=st.integers(0, 689), twice=st.booleans())
def test_the_first_row_without_weight_is_named(row, twice):
    arm = cgaskin.capsule_arm()
    v, f, j, w = _mesh(arm)
    w[row] = 0.0
    if twice:
        w[-1] = 0.0
    count = 2 if twice and row != len(w) - 1 else 1
    with pytest.raises(InvalidInputError, match=rf"vertex {row} has no weight at all \({count} such vertices\)"):
        arm.with_mesh(v, f, j, w)
    for make in (lambda: Rig(vertices=v, faces=f, joints=j, weights=w, skeleton=arm.skeleton),
                 lambda: dataclasses.replace(arm, weights=w)):
        with pytest.raises(InvalidInputError, match=rf"vertex {row} has no weight at all"):
            make()


def test_every_shipped_model_still_loads(models_dir):
    """The loaders apply the same rule: no shipped file has a vertex without weight (they load), and
    what they return passes the constructor's check unchanged."""
    files = sorted(p for p in models_dir.iterdir() if p.suffix in (".glb", ".gltf"))
    assert files
    for path in files:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")       # repaired weights (documented) are not the point here
            rig = cgaskin.load(path)
        assert (rig.weights > 0).any(axis=1).all(), path.name
        again = rig.with_mesh(*_mesh(rig), attributes=dict(rig.attributes))
        for a, b in zip(_mesh(rig), _mesh(again)):
            assert np.array_equal(a, b), path.name


# ---- item 2: bad arrays are refused where the rig is made, naming the row and the value ---------------------
def _nan_vertex(v, f, j, w):
    v[3, 1] = np.nan
    return v, f, j, w


def _face_out_of_range(v, f, j, w):
    f[5, 2] = len(v) + 7
    return v, f, j, w


def _negative_face(v, f, j, w):
    f[2, 0] = -1
    return v, f, j, w


def _negative_weight(v, f, j, w):
    w[4] = [1.5, -0.5, 0, 0]
    return v, f, j, w


def _joint_out_of_range(v, f, j, w):
    j[6, 0] = 99
    return v, f, j, w


BAD = {
    "NaN vertex": (_nan_vertex, r"vertex 3 has a non-finite position \[[-0-9.e]+, nan, [-0-9.e]+\]"),
    "face out of range": (_face_out_of_range, r"face 5 = \[\d+, \d+, 697\] refers to a vertex outside \[0, 690\)"),
    "negative face": (_negative_face, r"face 2 = \[-1, \d+, \d+\] refers to a vertex outside \[0, 690\)"),
    "float faces": (lambda v, f, j, w: (v, f.astype(np.float64), j, w),
                    r"faces must hold integer vertex indices, got dtype float64"),
    "negative weight": (_negative_weight, r"vertex 4 has negative weights \[1.5, -0.5, 0.0, 0.0\]"),
    "joint out of range": (_joint_out_of_range, r"vertex 6 is weighted to bone indices \[99.*\[0, 3\)"),
}


@pytest.mark.parametrize("bad", sorted(BAD))
def test_bad_arrays_are_refused_by_with_mesh_naming_row_and_value(bad):
    arm = cgaskin.capsule_arm()
    spoil, message = BAD[bad]
    arrays = spoil(*_mesh(arm))
    with pytest.raises(InvalidInputError, match=message):
        arm.with_mesh(*arrays)
    with pytest.raises(InvalidInputError, match=message):
        Rig(*arrays, skeleton=arm.skeleton)


@pytest.mark.parametrize("attributes, message", [
    ({"NORMAL": np.zeros((3, 3))}, r"attribute 'NORMAL' has 3 rows for 690 vertices"),
    ({"UV": np.full((690, 2), np.inf)}, r"attribute 'UV' holds a non-finite value.*at index \(0, 0\)"),
    ({"NAME": np.array(["x"] * 690)}, r"attribute 'NAME' must be numeric"),
])
def test_bad_attributes_are_refused_where_the_rig_is_made(attributes, message):
    arm = cgaskin.capsule_arm()
    with pytest.raises(InvalidInputError, match=message):
        arm.with_mesh(*_mesh(arm), attributes=attributes)


def test_the_skeleton_must_be_a_skeleton():
    arm = cgaskin.capsule_arm()
    with pytest.raises(InvalidInputError, match="skeleton must be a cgaskin.Skeleton, got dict"):
        Rig(*_mesh(arm), skeleton={})


# ---- item 3: the arrays are read-only, the caller's stay theirs ------------------------------------------------
def _arrays_of(rig):
    sk = rig.skeleton
    yield from (("vertices", rig.vertices), ("faces", rig.faces), ("joints", rig.joints), ("weights", rig.weights))
    yield from ((f"attribute {name}", values) for name, values in rig.attributes.items())
    yield from ((name, getattr(sk, name)) for name in ("parents", "rest_translations", "rest_rotations",
                                                        "rest_scales", "rest_matrices", "bone_nodes",
                                                        "inverse_bind"))


def test_a_rigs_arrays_cannot_be_edited(fox):
    cgaskin.tear(fox, *FOX_STROKES)                     # builds the caches that an edit would leave stale
    for name, values in _arrays_of(fox):
        assert not values.flags.writeable, name
        before = values.copy()
        with pytest.raises(ValueError, match="read-only"):
            values[...] = 0
        assert np.array_equal(values, before), name
    with pytest.raises(ValueError, match="read-only"):
        fox.vertices[:, 1] += 100
    with pytest.raises(TypeError, match="read-only"):
        fox.attributes["NORMAL"] = np.zeros((fox.n_vertices, 3))
    with pytest.raises(TypeError, match="read-only"):
        fox.attributes.pop("NORMAL")


def test_a_moved_copy_tears_where_it_now_is(fox):
    """The issue's repro: the edit that left the caches stale now goes through ``with_mesh``; the new
    rig tears at the new position exactly as the original tears at the old one."""
    torn = cgaskin.tear(fox, *FOX_STROKES)
    offset = np.array([0.0, 100.0, 0.0])
    v, f, j, w = _mesh(fox)
    moved = fox.with_mesh(v + offset, f, j, w, dict(fox.attributes))
    strokes = [[np.add(p, offset) for p in stroke] for stroke in FOX_STROKES]
    moved_torn = cgaskin.tear(moved, *strokes)
    assert moved_torn.n_vertices == torn.n_vertices > fox.n_vertices
    assert np.array_equal(moved_torn.faces, torn.faces)
    assert np.allclose(moved_torn.vertices, torn.vertices + offset, rtol=0, atol=1e-9 * 200)


def test_the_callers_arrays_are_copied_and_stay_writeable():
    arm = cgaskin.capsule_arm()
    mine = _mesh(arm)
    normals = np.array(arm.attributes["NORMAL"])
    originals = [a.copy() for a in mine + [normals]]
    rig = arm.with_mesh(*mine, attributes={"NORMAL": normals})
    built = Rig(*mine, skeleton=arm.skeleton, attributes={"NORMAL": normals})
    for r in (rig, built):
        for theirs, ours in zip(mine + [normals], (r.vertices, r.faces, r.joints, r.weights, r.attributes["NORMAL"])):
            assert theirs.flags.writeable and not ours.flags.writeable
            assert not np.shares_memory(theirs, ours)
    for theirs, original in zip(mine + [normals], originals):
        assert np.array_equal(theirs, original)
    mine[0][:, 1] += 100                            # the caller's own array: theirs to edit, the rig unmoved
    assert np.array_equal(rig.vertices, arm.vertices) and np.array_equal(built.vertices, arm.vertices)


def test_the_callers_skeleton_arrays_are_copied_and_stay_writeable():
    sk = cgaskin.capsule_arm().skeleton
    mine = {name: np.array(getattr(sk, name)) for name in ("parents", "rest_translations", "rest_rotations",
                                                            "rest_scales", "rest_matrices", "bone_nodes",
                                                            "inverse_bind")}
    copy = Skeleton(names=list(sk.names), **mine)
    for name, theirs in mine.items():
        ours = getattr(copy, name)
        assert theirs.flags.writeable and not ours.flags.writeable, name
        assert not np.shares_memory(theirs, ours) and np.array_equal(theirs, ours), name


def test_a_rig_made_of_read_only_arrays_skins_and_tears_like_its_source():
    """Internal operations never write into a rig's arrays: skinning, cut, tear and a session work on
    rigs whose arrays are read-only, and agree with the same rig rebuilt from fresh copies."""
    arm = cgaskin.capsule_arm()
    twin = arm.with_mesh(*_mesh(arm), attributes={k: np.array(v) for k, v in arm.attributes.items()})
    pose = arm.rest_pose().rotate(1, [1, 0, 0], 0.3)
    assert np.array_equal(cgaskin.skin(arm, pose), cgaskin.skin(twin, pose))
    strokes = (([0.6, 0.5, 0.0], [0.6, 0.0, 0.0]), ([0.9, 0.5, 0.0], [0.9, 0.0, 0.0]))
    for a, b in zip(_mesh(cgaskin.tear(arm, *strokes, pose=pose)), _mesh(cgaskin.tear(twin, *strokes, pose=pose))):
        assert np.array_equal(a, b)
    halves = [cgaskin.cut(r, [1, 0, 0], [1.2, 0, 0], cap=True) for r in (arm, twin)]
    for a, b in zip(*halves):
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    session = cgaskin.Surgery(arm)
    session.tear(*strokes)
    assert not session.rig.vertices.flags.writeable


# ---- the check's fast path (rigs made from rigs) gives what the full check gives ----------------------------
@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 6), n_bones=st.integers(1, 5),
       layout=st.sampled_from(["clean", "unused in front", "garbage joints", "duplicates", "sums off", "zero row"]))
def test_check_mesh_fast_path_agrees_with_the_full_check(monkeypatch_module, seed, k, n_bones, layout):
    """``check_mesh`` skips its repairs when the influences are already as it leaves them; with the
    shortcut disabled it must return the same arrays bit for bit, with the same warnings or error."""
    from cgaskin.animation import validate
    rng = np.random.default_rng(seed)
    n = 12
    vertices, faces = rng.normal(size=(n, 3)), rng.integers(0, n, size=(8, 3))
    joints = rng.integers(0, n_bones, size=(n, k))
    weights = rng.random((n, k)) * (rng.random((n, k)) < 0.7)
    weights[:, 0] += 0.1
    if layout == "clean":                          # what check_mesh made: the shortcut's case
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            vertices, faces, joints, weights = validate.check_mesh(vertices, faces, joints, weights, n_bones=n_bones)
        assert validate._clean_joints(joints, weights, n_bones) is not None
    elif layout == "unused in front":
        weights[:, 0] = 0.0
    elif layout == "garbage joints":
        joints[weights == 0] = n_bones + 3
    elif layout == "duplicates":
        joints[:, -1] = joints[:, 0]
    elif layout == "sums off":
        weights = weights / weights.sum(axis=1, keepdims=True) * (1 + 1e-12)
    elif layout == "zero row":
        weights[5] = 0.0

    def run():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                out = validate.check_mesh(vertices, faces, joints, weights, n_bones=n_bones)
            except InvalidInputError as exc:
                out = str(exc)
        return out, [str(w.message) for w in caught]

    fast, fast_warnings = run()
    with monkeypatch_module.context() as patch:
        patch.setattr(validate, "_clean_joints", lambda *args: None)
        full, full_warnings = run()
    assert fast_warnings == full_warnings
    if isinstance(full, str):
        assert fast == full
    else:
        for a, b in zip(fast, full):
            assert a.dtype == b.dtype and a.flags.c_contiguous == b.flags.c_contiguous and np.array_equal(a, b)
            assert a.tobytes() == b.tobytes()


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as patch:
        yield patch


def test_kernels_see_a_rigs_arrays_as_the_writeable_type_they_were_compiled_for():
    """numba compiles a read-only array apart (a second variant of each kernel, missing from
    ``cgaskin.precompile``): the kernels that only read a rig's arrays get the buffer behind them."""
    from numba import typeof

    from cgaskin._shared.frozen import kernel_array
    arm = cgaskin.capsule_arm()
    for values in (arm.vertices, arm.faces, arm.joints, arm.weights, arm.skeleton.parents, arm.skeleton.bone_nodes,
                   arm.attributes["NORMAL"]):
        buffer = kernel_array(values)
        assert buffer.flags.writeable and buffer.flags.c_contiguous and typeof(buffer).mutable
        assert buffer.shape == values.shape and buffer.dtype == values.dtype and np.shares_memory(buffer, values)
    mine = np.ones((3, 3))
    assert kernel_array(mine) is mine
    view = mine[:2]
    view.flags.writeable = False
    assert kernel_array(view) is view               # not the whole of its base: left as it is


def test_rigs_made_by_operations_keep_the_rule():
    """The rigs cgaskin's own operations make without checking them again (``Rig._of_checked``: a cut's
    halves, capped or not, a torn rig, a session's snapshot after a cut) pass the check unchanged."""
    rig = cgaskin.capsule_arm()
    made = list(cgaskin.cut(rig, [1, 0.3, 0], [1.5, 0, 0])) + list(cgaskin.cut(rig, [1, 0.3, 0], [1.5, 0, 0], cap=True))
    made.append(cgaskin.tear(rig, [[1.2, 1.0, 0.1], [1.2, 0.0, 0.1]], [[1.8, 1.0, 0.1], [1.8, 0.0, 0.1]], opening=0.01))
    session = cgaskin.Surgery(rig)
    session.cut([1, 0, 0], [2.2, 0, 0])
    made.append(session.rig)
    for result in made:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            again = Rig(result.vertices, result.faces, result.joints, result.weights, result.skeleton,
                        result.clips, dict(result.attributes), result.name)
        for name in ("vertices", "faces", "joints", "weights"):
            assert np.array_equal(getattr(again, name), getattr(result, name)), name
            assert not getattr(result, name).flags.writeable


def test_a_clips_arrays_are_read_only_copies():
    """A clip's key arrays are read-only copies (its packed arrays are kept): an edit in place raises
    instead of being silently ignored by later samples; the maker's arrays stay writeable."""
    times, values = np.array([0.0, 1.0]), np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.6, 0.8]])
    channel = cgaskin.Channel(node=1, path="rotation", interpolation="LINEAR", times=times, values=values)
    clip = cgaskin.Clip("turn", [channel])
    assert isinstance(clip.channels, tuple) and times.flags.writeable and values.flags.writeable
    values[1] = [0.0, 0.0, 0.0, 1.0]
    assert clip.channels[0].values[1, 2] == 0.6
    with pytest.raises(ValueError, match="read-only"):
        clip.channels[0].times[1] = 2.0


def test_a_pickled_rig_comes_back_read_only(fox):
    """Pickling (a Dask worker, a saved notebook) keeps the rule: the rig, its skeleton and clips come
    back equal and read-only."""
    import pickle
    again = pickle.loads(pickle.dumps(fox))
    arrays = [again.vertices, again.faces, again.joints, again.weights, *again.attributes.values(),
              again.skeleton.inverse_bind, again.skeleton.parents, again.clips[0].channels[0].times]
    assert all(not a.flags.writeable for a in arrays)
    with pytest.raises(TypeError):
        again.attributes["_X"] = again.vertices
    np.testing.assert_array_equal(cgaskin.skin(again, again.pose(0, 0.3)), cgaskin.skin(fox, fox.pose(0, 0.3)))


@pytest.mark.parametrize("name", ["vertices", "faces", "joints", "weights"])
def test_an_array_made_writeable_again_is_refused_not_used_stale(name):
    """numpy lets ``rig.vertices.flags.writeable = True`` through (the buffer behind the read-only view is
    writeable): an edit in place would leave the rig's topology and BVH stale. Every operation refuses
    such a rig, also after one that cached those values (issue 43 D13)."""
    rig = cgaskin.capsule_arm()
    cgaskin.cut(rig, [1, 0, 0], [1.5, 0, 0])               # (its topology and BVH are cached now)
    getattr(rig, name).flags.writeable = True
    if name == "vertices":
        rig.vertices[:, 0] += 10.0                          # moved away: a stale BVH would miss the plane
    blade = ([1.0, 0.05, 1.0], [1.0, 0.05, 0.0]), ([1.5, 0.05, 1.0], [1.5, 0.05, 0.0])
    for operation in (lambda: cgaskin.cut(rig, [1, 0, 0], [1.5, 0, 0]), lambda: cgaskin.skin(rig),
                      lambda: cgaskin.tear(rig, *blade), lambda: cgaskin.drill(rig, [1.0, 0, -1], [1.0, 0, 1], 0.1),
                      lambda: cgaskin.Surgery(rig).cut([1, 0, 0], [1.5, 0, 0])):
        with pytest.raises(InvalidInputError, match=f"rig.{name} was made writeable again.*with_mesh"):
            operation()
