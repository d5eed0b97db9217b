"""Poses, clips and skinning of real models against an independent glTF implementation."""
import numpy as np
import pytest

import cgaskin
from cgaskin import versor
from cgaskin.errors import InvalidInputError

from tests.helpers.gltf_reference import reference_skin

GLTF_MODELS = ["Fox.glb", "simple_skin.gltf", "Arm5.glb", "3Cylinder4bones.glb", "PlaneWith3Bones.glb",
               "quad_skin.glb"]


def diagonal(points):
    return float(np.linalg.norm(np.ptp(points, axis=0)))


@pytest.fixture(scope="module")
def rigs(models_dir):
    return {name: cgaskin.load(models_dir / name) for name in GLTF_MODELS}


@pytest.mark.parametrize("name", GLTF_MODELS)
def test_rest_pose_matches_gltf_reference(rigs, models_dir, name):
    rig = rigs[name]
    expected = reference_skin(models_dir / name, None, 0.0, max_influences=4)
    assert np.abs(cgaskin.skin(rig) - expected).max() <= 1e-9 * diagonal(expected)


@pytest.mark.parametrize("name", ["Fox.glb", "simple_skin.gltf"])
def test_every_clip_matches_gltf_reference(rigs, models_dir, name):
    rig = rigs[name]
    assert rig.clips
    for index, clip in enumerate(rig.clips):
        # before the first key, on keys, between keys, after the last key
        times = np.concatenate([[-0.5, 0.0], np.linspace(0, clip.duration, 23), [clip.duration + 1]])
        times = np.concatenate([times, clip.channels[0].times[:5]])
        for t in times:
            expected = reference_skin(models_dir / name, index, t, max_influences=4)
            got = cgaskin.skin(rig, rig.pose(clip.name, t))
            assert np.abs(got - expected).max() <= 1e-9 * diagonal(expected), (clip.name, t)


@pytest.mark.parametrize("name", ["Arm5.glb", "3Cylinder4bones.glb", "PlaneWith3Bones.glb", "Fox.glb"])
def test_bind_pose_returns_stored_vertices(rigs, name):
    rig = rigs[name]
    got = cgaskin.skin(rig, rig.bind_pose())
    assert np.abs(got - rig.vertices).max() <= 1e-9 * diagonal(rig.vertices)


def test_linear_rotation_blend_is_close_to_slerp(rigs):
    rig = rigs["Fox.glb"]
    t = 0.37
    slerp = cgaskin.skin(rig, rig.pose("Walk", t))
    nlerp = cgaskin.skin(rig, rig.pose("Walk", t, rotation_blend="linear"))
    d = diagonal(slerp)
    assert 0 < np.abs(slerp - nlerp).max() < 1e-2 * d


def _subtree(rig, node):
    parents = rig.skeleton.parents
    inside = np.zeros(rig.skeleton.n_nodes, bool)
    inside[node] = True
    for i in range(node + 1, len(parents)):
        if parents[i] >= 0 and inside[parents[i]]:
            inside[i] = True
    return inside


@pytest.mark.parametrize("name,clip_time", [("Arm5.glb", None), ("Fox.glb", 0.4), ("3Cylinder4bones.glb", None)])
@pytest.mark.parametrize("scale", [0.25, 1.7])
def test_dilation_scales_descendants_about_the_joint(rigs, name, clip_time, scale):
    rig = rigs[name]
    base = rig.rest_pose() if clip_time is None else rig.pose(0, clip_time)
    sk = rig.skeleton
    bone_counts = np.bincount(rig.joints[rig.weights > 0], minlength=sk.n_bones)
    # a bone node with a parent and a real subtree of weighted vertices
    for b in np.argsort(-bone_counts):
        node = int(sk.bone_nodes[b])
        if sk.parents[node] < 0:
            continue
        inside_nodes = _subtree(rig, node)
        inside_bones = inside_nodes[sk.bone_nodes]
        only_subtree = np.all(inside_bones[rig.joints] | (rig.weights == 0), axis=1)
        if only_subtree.sum() >= 10:
            break
    before = cgaskin.skin(rig, base)
    after = cgaskin.skin(rig, base.dilate(node, scale))
    pivot = base.global_matrices()[node][:3, 3]
    expected = pivot + scale * (before[only_subtree] - pivot)
    assert np.abs(after[only_subtree] - expected).max() <= 1e-9 * diagonal(before)
    # vertices with no weight in the subtree do not move
    outside = np.all(~inside_bones[rig.joints] | (rig.weights == 0), axis=1)
    assert np.array_equal(after[outside], before[outside])


def test_edits_rotate_translate_compose(rigs):
    rig = rigs["Arm5.glb"]
    pose = rig.rest_pose()
    node = rig.skeleton.names[5]
    edited = pose.rotate(node, [0, 0, 1], 0.3).translate(node, [0.1, 0, 0]).dilate(node, 1.2)
    g0, g1 = pose.global_matrices(), edited.global_matrices()
    i = rig.skeleton.node_index(node)
    parent = g0[rig.skeleton.parents[i]]
    local0 = np.linalg.solve(parent, g0[i])
    local1 = np.linalg.solve(parent, g1[i])
    pivot = local0[:3, 3]
    expected = (versor.to_matrix(versor.translator([0.1, 0, 0]))
                @ versor.to_matrix(versor.compose(versor.translator(pivot), versor.rotor([0, 0, 1], 0.3),
                                                  versor.translator(-pivot)))
                @ local0 @ versor.to_matrix(versor.dilator(1.2)))
    assert np.allclose(local1, expected, atol=1e-12 * np.abs(expected).max())
    # the original pose is unchanged (poses are values)
    assert np.array_equal(pose.global_matrices(), g0)


def test_local_frame_rotation(rigs):
    rig = rigs["PlaneWith3Bones.glb"]
    pose = rig.rest_pose()
    i = 1
    g0 = pose.global_matrices()
    g1 = pose.rotate(i, [1, 0, 0], 0.5, frame="local").global_matrices()
    assert np.allclose(g1[i], g0[i] @ versor.to_matrix(versor.rotor([1, 0, 0], 0.5)), atol=1e-12)


def test_normals_follow_rotation(rigs):
    rig = cgaskin.capsule_arm()
    pose = rig.rest_pose().rotate(0, [0, 0, 1], np.pi / 2)
    n = cgaskin.skin_normals(rig, pose)
    assert np.allclose(np.linalg.norm(n, axis=1), 1)
    # the whole arm hangs on the root: vertices weighted only to the root turn with it
    root_only = rig.weights[:, 0] == 1.0
    expected = rig.attributes["NORMAL"][root_only] @ versor.to_matrix(versor.rotor([0, 0, 1], np.pi / 2))[:3, :3].T
    assert np.allclose(n[root_only], expected / np.linalg.norm(expected, axis=1, keepdims=True), atol=1e-12)


def test_bad_joint_and_clip_names(rigs):
    rig = rigs["Fox.glb"]
    with pytest.raises(InvalidInputError, match="valid joints"):
        rig.rest_pose().rotate("no_such_joint", [0, 0, 1], 1.0)
    with pytest.raises(InvalidInputError, match="valid clips.*Survey"):
        rig.pose("Dance", 0.0)
    with pytest.raises(InvalidInputError):
        rig.pose(0, float("nan"))
    with pytest.raises(InvalidInputError, match="rotation_blend"):
        rig.pose(0, 0.0, rotation_blend="cubic")
    with pytest.raises(InvalidInputError, match="scale"):
        rig.rest_pose().dilate(3, -1.0)
    with pytest.raises(InvalidInputError, match="axis"):
        rig.rest_pose().rotate(3, [0, 0, 0], 1.0)


def test_skin_refuses_what_is_not_a_pose_of_the_rig(rigs):
    fox, arm = rigs["Fox.glb"], rigs["Arm5.glb"]
    for function in (cgaskin.skin, cgaskin.skin_normals):
        with pytest.raises(InvalidInputError, match="pose must be a cgaskin.Pose"):
            function(arm, "rest")
        with pytest.raises(InvalidInputError, match="another skeleton"):
            function(arm, fox.rest_pose())


# --- clips from generated keyframes ---------------------------------------------------------------

def test_clip_from_edited_poses_reproduces_its_keys(rigs, tmp_path):
    rig = rigs["Fox.glb"]
    neck, tail, root = "b_Neck_04", "b_Tail01_012", "b_Root_00"
    start = rig.pose("Walk", 0.3)
    keys = [start,
            start.rotate(neck, [0, 0, 1], np.radians(50)).dilate(tail, 1.8),
            start.rotate(neck, [1, 0, 0], np.radians(-170)).translate(root, [0, 20, 5]).dilate(tail, 0.5)]
    times = [0.5, 1.0, 2.5]
    clip = cgaskin.clip_from_poses("nod", times, keys)
    animated = {rig.skeleton.names[c.node] for c in clip.channels}
    assert {neck, tail, root} <= animated and len(clip.channels) % 3 == 0
    assert clip.duration == 2.5
    posed = rig.with_clips(clip)
    assert [c.name for c in posed.clips] == ["Survey", "Walk", "Run", "nod"] and len(rig.clips) == 3
    for t, key in zip(times, keys):
        expected = cgaskin.skin(rig, key)
        got = cgaskin.skin(posed, posed.pose("nod", t))
        assert np.abs(got - expected).max() <= 1e-12 * diagonal(expected)
    # between keys 0 and 1 the neck turns half way and the tail's scale is halfway (linear)
    half = start.rotate(neck, [0, 0, 1], np.radians(25)).dilate(tail, 1.4)
    expected = cgaskin.skin(rig, half)
    assert np.abs(cgaskin.skin(posed, posed.pose("nod", 0.75)) - expected).max() <= 1e-12 * diagonal(expected)
    # STEP holds each key; save -> load keeps the clip
    step = rig.with_clips(cgaskin.clip_from_poses("held", times, keys, interpolation="STEP"))
    np.testing.assert_array_equal(cgaskin.skin(step, step.pose("held", 0.99)), cgaskin.skin(step, step.pose("held", 0.5)))
    back = cgaskin.load(cgaskin.save(posed, tmp_path / "nod.glb"))
    expected = cgaskin.skin(rig, keys[2])
    assert np.abs(cgaskin.skin(back, back.pose("nod", 2.5)) - expected).max() <= 1e-6 * diagonal(expected)


def test_clip_from_poses_of_the_procedural_arm_animates_a_cut_half():
    rig = cgaskin.capsule_arm()
    rest = rig.rest_pose()
    elbow = rig.skeleton.names[1]
    clip = cgaskin.clip_from_poses("bend", [0, 1], [rest, rest.rotate(elbow, [0, 0, 1], np.radians(90))])
    upper, lower = cgaskin.cut(rig.with_clips(clip), [1, 0, 0], [1.5, 0, 0])
    for half in (upper, lower):
        assert half.clips[-1].name == "bend"
        np.testing.assert_allclose(cgaskin.skin(half, half.pose("bend", 1.0)),
                                   cgaskin.skin(half, rest.rotate(elbow, [0, 0, 1], np.radians(90))),
                                   rtol=0, atol=1e-12)


def test_clip_from_poses_refuses_bad_keys(rigs):
    fox, arm = rigs["Fox.glb"], rigs["Arm5.glb"]
    rest = fox.rest_pose()
    for args, message in [
        (("", [0], [rest]), "non-empty string"),
        (("c", [], []), "non-empty and of one length"),
        (("c", [0, 1], [rest]), "non-empty and of one length"),
        (("c", [1, 1], [rest, rest]), "strictly increasing"),
        (("c", [0, np.nan], [rest, rest]), "non-finite"),
        (("c", [0, 1], [rest, "pose"]), r"poses\[1\] must be a cgaskin.Pose"),
        (("c", [0, 1], [rest, arm.rest_pose()]), "another skeleton"),
    ]:
        with pytest.raises(InvalidInputError, match=message):
            cgaskin.clip_from_poses(*args)
    with pytest.raises(InvalidInputError, match="interpolation"):
        cgaskin.clip_from_poses("c", [0], [rest], interpolation="CUBICSPLINE")
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    exact = [None] * fox.skeleton.n_nodes
    exact[3] = sheared
    skeleton = fox.skeleton
    bad = cgaskin.Pose.from_trs(skeleton, skeleton.rest_translations, skeleton.rest_rotations,
                                skeleton.rest_scales, exact)
    with pytest.raises(InvalidInputError, match="sheared"):
        cgaskin.clip_from_poses("c", [0, 1], [rest, bad])
    clip = cgaskin.clip_from_poses("Walk", [0], [rest.dilate(3, 2.0)])
    with pytest.raises(InvalidInputError, match="already has a clip named 'Walk'"):
        fox.with_clips(clip)
    with pytest.raises(InvalidInputError, match="node"):
        cgaskin.capsule_arm().with_clips(clip)
