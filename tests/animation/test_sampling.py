"""The compiled clip sampler (``rig.pose``, ``rig.poses``) against the independent glTF sampler of
tests/helpers/gltf_reference.py: pose fields at random times (on keys, between keys, before the first
and after the last) on every shared model with clips and on random clips of every interpolation and
path; skinning at those times against the reference skinning; batches equal single frames exactly;
bad input."""
import dataclasses
import math
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import cgaskin
from cgaskin import Channel, Clip, Pose, Poses
from cgaskin.algebra.transforms import trs_matrix
from cgaskin.animation.sampling import shear_nodes
from cgaskin.errors import InvalidInputError

from tests.helpers.gltf_reference import reference_skin, sample

POSE_TOL = 1e-12          # pose fields, relative to the largest coefficient (and at least 1)
SKIN_TOL = 1e-9           # skinned positions, relative to the bounding-box diagonal (as test_pose.py)
PATHS = {"translation": 0, "rotation": 1, "scale": 2}


@pytest.fixture(scope="module")
def clip_models(models_dir):
    """Every shared glTF model that has clips: {file name: rig}."""
    out = {}
    for path in sorted(list(models_dir.glob("*.glb")) + list(models_dir.glob("*.gltf"))):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rig = cgaskin.load(path)
        if rig.clips:
            out[path.name] = rig
    assert {"Fox.glb", "simple_skin.gltf"} <= set(out)
    return out


# ---- the oracle ------------------------------------------------------------------------------------
def _nlerp(a, b, u):
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    q = (1 - u) * a + u * (b if a @ b >= 0 else -b)
    return q / np.linalg.norm(q)


def _reference_value(channel, t, rotation_blend):
    """One channel at t: the glTF reference sampler (its slerp), or the normalised linear blend."""
    times, values = channel.times, channel.values.reshape(-1, channel.values.shape[-1])
    if (rotation_blend == "linear" and channel.path == "rotation" and channel.interpolation == "LINEAR"
            and times[0] < t < times[-1]):
        k = int(np.searchsorted(times, t, side="right")) - 1
        return _nlerp(values[k], values[k + 1], (t - times[k]) / (times[k + 1] - times[k]))
    return sample(times, values, channel.interpolation, channel.path, t)


def reference_pose(skeleton, clip, t, rotation_blend="slerp"):
    """The pose that ``Pose.from_trs`` makes of the reference sampler's TRS: unanimated nodes keep
    their rest TRS (and a sheared rest matrix), animated ones are TRS."""
    trs = [skeleton.rest_translations.copy(), skeleton.rest_rotations.copy(), skeleton.rest_scales.copy()]
    exact = shear_nodes(skeleton)
    for channel in clip.channels:
        trs[PATHS[channel.path]][channel.node] = _reference_value(channel, t, rotation_blend)
        exact[channel.node] = None
    return Pose.from_trs(skeleton, *trs, exact)


def assert_pose_close(got, expected, what):
    assert np.array_equal(got.similar, expected.similar), what
    for name in ("versors", "matrices"):
        a, b = getattr(got, name), getattr(expected, name)
        err = np.abs(a - b).max() / max(1.0, np.abs(b).max())
        assert err <= POSE_TOL, (what, name, err)


def diagonal(points):
    return float(np.linalg.norm(np.ptp(points, axis=0)))


# ---- times -----------------------------------------------------------------------------------------
TIME_KINDS = ("key", "between", "before", "after", "inside")


def clip_time(clip, kind, pick, fraction):
    """A time of ``kind`` in ``clip``: a key time of some channel, a time between two of its keys,
    before every key, after every key, or anywhere from the first key to the last."""
    channel = clip.channels[pick % len(clip.channels)]
    times = channel.times
    first = min(float(c.times[0]) for c in clip.channels)
    if kind == "key":
        return float(times[pick % len(times)])
    if kind == "between" and len(times) > 1:
        k = pick % (len(times) - 1)
        return float(times[k] + fraction * (times[k + 1] - times[k]))
    if kind == "before":
        return first - 10.0 * fraction - 1e-9
    if kind == "after":
        return clip.duration + 10.0 * fraction + 1e-9
    return first + fraction * (clip.duration - first)


times_spec = st.tuples(st.sampled_from(TIME_KINDS), st.integers(0, 10 ** 6), st.floats(0.0, 1.0))


# ---- real models -----------------------------------------------------------------------------------
@given(spec=times_spec, blend=st.sampled_from(["slerp", "linear"]))
def test_sampled_poses_equal_the_reference_on_every_model(clip_models, spec, blend):
    for name, rig in clip_models.items():
        for clip in rig.clips:
            t = clip_time(clip, *spec)
            assert_pose_close(rig.pose(clip.name, t, rotation_blend=blend),
                              reference_pose(rig.skeleton, clip, t, blend), (name, clip.name, t, blend))


@given(spec=times_spec)
def test_skinning_at_sampled_times_equals_the_reference(clip_models, models_dir, spec):
    for name, rig in clip_models.items():
        for index, clip in enumerate(rig.clips):
            t = clip_time(clip, *spec)
            expected = reference_skin(models_dir / name, index, t, max_influences=4)
            got = cgaskin.skin(rig, rig.pose(index, t))
            assert np.abs(got - expected).max() <= SKIN_TOL * diagonal(expected), (name, clip.name, t)


@given(specs=st.lists(times_spec, min_size=0, max_size=12), blend=st.sampled_from(["slerp", "linear"]))
def test_batches_equal_single_frames_exactly(clip_models, specs, blend):
    for rig in clip_models.values():
        for clip in rig.clips:
            times = np.array([clip_time(clip, *spec) for spec in specs])      # any order, repeats
            poses = rig.poses(clip.name, times, rotation_blend=blend)
            assert isinstance(poses, Poses) and len(poses) == len(times)
            assert np.array_equal(poses.times, times)
            vertices = cgaskin.skin(rig, poses)
            affines = poses.bone_affines()
            assert vertices.shape == (len(times), rig.n_vertices, 3)
            for i, t in enumerate(times):
                pose = rig.pose(clip.name, t, rotation_blend=blend)
                for field in ("versors", "matrices", "similar"):
                    assert np.array_equal(getattr(poses[i], field), getattr(pose, field)), (clip.name, t, field)
                assert np.array_equal(affines[i], pose.bone_affines())
                assert np.array_equal(vertices[i], cgaskin.skin(rig, pose))


def test_the_clips_cursor_never_changes_a_frame(clip_models):
    """The cursor (each channel's last key interval) is shared by every call on a clip: frames asked
    forward, backward, shuffled and from four threads at once equal each frame asked alone first."""
    from concurrent.futures import ThreadPoolExecutor
    rng = np.random.default_rng(7)

    def fields(pose):
        return np.concatenate([pose.versors.ravel(), pose.matrices.ravel()])

    for rig in clip_models.values():
        for clip in rig.clips:
            times = np.concatenate([np.linspace(-0.1, clip.duration + 0.1, 61), clip.channels[0].times[:40]])
            alone = {t: fields(rig.with_clips(Clip("alone", clip.channels)).pose("alone", t))   # a new cursor
                     for t in times}
            asked = np.concatenate([times, times[::-1], rng.permutation(times)])
            for t in asked:
                assert np.array_equal(fields(rig.pose(clip.name, t)), alone[t]), (clip.name, t)
            asked = np.tile(rng.permutation(times), 4)
            with ThreadPoolExecutor(4) as pool:
                threaded = list(pool.map(lambda t: fields(rig.pose(clip.name, t)), asked))
            for t, got in zip(asked, threaded):
                assert np.array_equal(got, alone[t]), (clip.name, t)


def test_poses_frames_and_slices(clip_models):
    rig = clip_models["Fox.glb"]
    times = np.linspace(-1.0, 2.0, 7)
    poses = rig.poses("Walk", times)
    assert [p.versors.tolist() for p in poses] == [poses[i].versors.tolist() for i in range(7)]
    assert np.array_equal(poses[-1].matrices, poses[6].matrices)
    part = poses[2:5]
    assert isinstance(part, Poses) and len(part) == 3 and np.array_equal(part.times, times[2:5])
    assert np.array_equal(cgaskin.skin(rig, part), cgaskin.skin(rig, poses)[2:5])
    assert np.array_equal(part.bone_affines(), poses.bone_affines()[2:5])
    # a frame is a Pose of its own: editing it changes neither the batch nor the other frames
    edited = poses[3].rotate("b_Neck_04", [0, 0, 1], 0.5)
    assert not np.array_equal(edited.versors, poses.versors[3])
    poses[3].versors[:] = 0
    assert np.array_equal(poses[3].versors, rig.pose("Walk", times[3]).versors)
    out = np.empty((7, rig.n_vertices, 3))
    assert cgaskin.skin(rig, poses, out=out) is out
    for bad in (7, -8):
        with pytest.raises(InvalidInputError, match="out of range"):
            poses[bad]
    with pytest.raises(InvalidInputError, match="frame number or a slice"):
        poses["1"]
    with pytest.raises(InvalidInputError, match="out must be"):
        cgaskin.skin(rig, poses, out=np.empty((6, rig.n_vertices, 3)))
    with pytest.raises(InvalidInputError, match="another skeleton"):
        cgaskin.skin(clip_models["simple_skin.gltf"], poses)


def test_times_outside_the_keys_clamp(clip_models):
    for rig in clip_models.values():
        for clip in rig.clips:
            first = min(float(c.times[0]) for c in clip.channels)
            for outside, inside in ((first - 5.0, first), (-1e300, first), (clip.duration + 3.0, clip.duration),
                                    (1e300, clip.duration)):
                a, b = rig.pose(clip.name, outside), rig.pose(clip.name, inside)
                assert np.array_equal(a.versors, b.versors) and np.array_equal(a.matrices, b.matrices)


def test_edits_of_a_sampled_pose(clip_models):
    rig = clip_models["Fox.glb"]
    got = rig.pose("Run", 0.37)
    expected = reference_pose(rig.skeleton, rig.clips[2], 0.37)
    for edit in (lambda p: p.rotate("b_Neck_04", [0, 0, 1], 0.7), lambda p: p.translate("b_Root_00", [1, 2, 3]),
                 lambda p: p.dilate("b_Tail01_012", 1.8), lambda p: p.rotate(5, [1, 0, 0], -0.4, frame="local")):
        assert_pose_close(edit(got), edit(expected), "edit")
        expected_vertices = cgaskin.skin(rig, edit(expected))
        assert np.abs(cgaskin.skin(rig, edit(got)) - expected_vertices).max() <= 1e-12 * diagonal(expected_vertices)


# ---- random clips of every interpolation and path ----------------------------------------------------
@st.composite
def random_clips(draw, n_nodes, favoured):
    """A clip of 1-8 channels on random nodes (often ``favoured``): every path and interpolation, 1-6 keys starting
    anywhere, rotations with sign flips and nearly equal keys, uniform, non-uniform and zero scales."""
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    channels = []
    for _ in range(draw(st.integers(1, 8))):
        path = draw(st.sampled_from(list(PATHS)))
        interpolation = draw(st.sampled_from(["STEP", "LINEAR", "CUBICSPLINE"]))
        k = draw(st.integers(1, 6))
        times = rng.uniform(-2, 2) + np.cumsum(rng.uniform(0.01, 1.0, k))
        width = 4 if path == "rotation" else 3
        if path == "rotation":
            values = rng.normal(size=(k, 4))
            values /= np.linalg.norm(values, axis=1, keepdims=True)
            values *= rng.choice([-1.0, 1.0], size=(k, 1))          # either hemisphere
            if k > 1 and draw(st.booleans()):                      # nearly equal neighbours
                values[1] = values[0] + rng.normal(size=4) * 10.0 ** -rng.uniform(4, 12)
        elif path == "scale":
            kind = draw(st.sampled_from(["uniform", "one", "free", "zero"]))
            s = rng.uniform(0.2, 3.0, (k, 1 if kind != "free" else 3))
            values = np.broadcast_to(1.0 if kind == "one" else (0.0 if kind == "zero" else s), (k, 3)).copy()
        else:
            values = rng.normal(size=(k, 3)) * 10.0
        if interpolation == "CUBICSPLINE":
            tangents = rng.normal(size=(k, 2, width))
            values = np.stack([tangents[:, 0], values, tangents[:, 1]], axis=1)
        node = favoured if draw(st.booleans()) else int(rng.integers(n_nodes))
        channels.append(Channel(node, path, interpolation, times, values))
    return Clip("random", tuple(channels))


def sheared_skeleton(skeleton, node):
    """``skeleton`` with a sheared rest matrix at ``node`` (its rest TRS stays the nearest TRS)."""
    matrices = skeleton.rest_matrices.copy()
    shear = np.eye(4)
    shear[0, 1] = 0.4
    matrices[node] = matrices[node] @ shear
    return dataclasses.replace(skeleton, rest_matrices=matrices)


@given(data=st.data(), spec=times_spec, blend=st.sampled_from(["slerp", "linear"]))
def test_random_clips_equal_the_reference(clip_models, data, spec, blend):
    rig = clip_models["Fox.glb"]
    sheared = data.draw(st.integers(0, rig.skeleton.n_nodes - 1))
    skeleton = sheared_skeleton(rig.skeleton, sheared)
    assert sum(e is not None for e in shear_nodes(skeleton)) == 1
    clip = data.draw(random_clips(skeleton.n_nodes, sheared))
    t = clip_time(clip, *spec)
    got = Pose.from_clip(skeleton, clip, t, blend)
    assert_pose_close(got, reference_pose(skeleton, clip, t, blend), (t, blend))
    times = np.array([t, clip_time(clip, "inside", 3, 0.5), t])
    batch = Poses.from_clip(skeleton, clip, times, blend)
    assert np.array_equal(batch.versors[0], got.versors) and np.array_equal(batch.matrices[2], got.matrices)


def test_slerp_takes_the_shorter_arc_and_holds_tiny_angles():
    rig = cgaskin.capsule_arm()
    for angle in (0.0, 1e-12, 1e-7, 0.3, 3.0, math.pi - 1e-9):
        q1 = np.array([0, 0, math.sin(angle / 2), math.cos(angle / 2)])
        for sign in (1.0, -1.0):
            clip = Clip("c", (Channel(1, "rotation", "LINEAR", np.array([0.0, 1.0]),
                                      np.array([[0, 0, 0, 1.0], sign * q1])),))
            for u in (0.25, 0.5):
                got = Pose.from_clip(rig.skeleton, clip, u)
                q = got.matrices[1][:3, :3]
                half = u * angle                      # the shorter arc about z
                np.testing.assert_allclose(q[:2, :2], [[math.cos(half), -math.sin(half)],
                                                       [math.sin(half), math.cos(half)]], atol=1e-12)


# ---- bad input ---------------------------------------------------------------------------------------
def test_bad_times_and_clips(clip_models):
    rig = clip_models["Fox.glb"]
    for t, message in [(float("nan"), "time must be finite"), (float("inf"), "time must be finite"),
                       (-np.inf, "time must be finite"), ("0.3", "time must be a real number"),
                       (None, "time must be a real number"), (True, "time must be a real number"),
                       ([0.3], "time must be a real number")]:
        with pytest.raises(InvalidInputError, match=message):
            rig.pose("Walk", t)
    assert np.array_equal(rig.pose("Walk", np.float32(0.25)).versors, rig.pose("Walk", 0.25).versors)
    assert np.array_equal(rig.pose("Walk", 1).versors, rig.pose("Walk", 1.0).versors)
    with pytest.raises(InvalidInputError, match="valid clips.*Survey"):
        rig.poses("Dance", [0.0])
    for times, message in [([[0.0, 1.0]], "1-dimensional"), (0.5, "1-dimensional"),
                           ([0.0, np.nan], "non-finite"), ([0.0, np.inf], "non-finite"), (["a"], "numeric")]:
        with pytest.raises(InvalidInputError, match=message):
            rig.poses("Walk", times)
    with pytest.raises(InvalidInputError, match="rotation_blend"):
        rig.poses("Walk", [0.0], rotation_blend="cubic")
    assert len(rig.poses("Walk", [])) == 0 and cgaskin.skin(rig, rig.poses("Walk", [])).shape == (0, rig.n_vertices, 3)


def test_bad_channels_are_named():
    arm = cgaskin.capsule_arm()
    t = np.array([0.0, 1.0])
    for channel, message in [
        (Channel(1, "weights", "LINEAR", t, np.zeros((2, 3))), "path must be one of"),
        (Channel(1, "rotation", "SMOOTH", t, np.zeros((2, 4))), "interpolation must be one of"),
        (Channel(1, "rotation", "LINEAR", t, np.zeros((2, 4))), "rotation key 0 has zero length"),
        (Channel(1, "scale", "LINEAR", np.array([1.0, 0.5]), np.ones((2, 3))), "strictly increasing"),
        (Channel(1, "scale", "CUBICSPLINE", t, np.ones((2, 3))), r"shape \(2, 3, 3\)"),
        (Channel(1, "translation", "STEP", t, np.array([[0, 0, 0], [0, np.nan, 0]])), "finite"),
        (Channel(-1, "translation", "STEP", t, np.zeros((2, 3))), "node must be"),
        (Channel(99, "translation", "STEP", t, np.zeros((2, 3))), "animates node 99"),
    ]:
        with pytest.raises(InvalidInputError, match=message):
            Pose.from_clip(arm.skeleton, Clip("bad", (channel,)), 0.5)
    huge = Clip("huge", (Channel(1, "scale", "STEP", t, np.array([[1.0] * 3, [1e13] * 3])),))
    with pytest.raises(InvalidInputError, match="uniform scale outside"):
        Pose.from_clip(arm.skeleton, huge, 1.5)
    with pytest.raises(InvalidInputError, match=r"times\[1\]"):
        Poses.from_clip(arm.skeleton, huge, [0.5, 1.5])


def test_a_clip_sampled_on_two_skeletons_is_checked_and_sampled_on_each():
    """A clip's prepared kernel arguments are kept for the skeleton it was last sampled on: another
    skeleton (with too few nodes, or other rest transforms) gets its own, never the kept ones."""
    small, large = cgaskin.capsule_arm(n_joints=2), cgaskin.capsule_arm(n_joints=5)
    t = np.array([0.0, 1.0])
    clip = Clip("bend", (Channel(3, "rotation", "LINEAR", t, np.array([[0, 0, 0, 1.0], [0, 0, 0.6, 0.8]])),))
    on_large = Pose.from_clip(large.skeleton, clip, 0.5)
    with pytest.raises(InvalidInputError, match="animates node 3"):
        Pose.from_clip(small.skeleton, clip, 0.5)
    sk = large.skeleton
    shifted = dataclasses.replace(sk, rest_translations=sk.rest_translations + 1.0,
                                  rest_matrices=trs_matrix(sk.rest_translations + 1.0, sk.rest_rotations,
                                                           sk.rest_scales))
    on_shifted = Pose.from_clip(shifted, clip, 0.5)
    assert not np.array_equal(on_shifted.matrices[0], on_large.matrices[0])
    assert np.array_equal(Pose.from_clip(large.skeleton, clip, 0.5).versors, on_large.versors)


def test_clips_are_found_by_name_after_the_list_changes():
    rig = cgaskin.capsule_arm()
    first = rig.clips[0]
    assert rig.clip_index(first.name) == 0
    rig.clips.insert(0, Clip("other", ()))      # a list a user can edit: names are looked up again
    assert rig.clip_index(first.name) == 1 and rig.clip_index("other") == 0
