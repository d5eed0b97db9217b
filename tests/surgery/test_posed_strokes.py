"""Strokes on a playing model: a stroke in a pose poses only what its blade reaches, through bounds that
hold the skinned surface in every pose, and gives what tearing the fully skinned surface gives.

Oracles: ``cgaskin.skin`` of the whole mesh (the bounds never miss a skinned vertex; the posed tree's
first hit is the brute-force BVH's of the skinned surface), a BVH built over the whole skinned surface
(the old way: ``tear_stroke(..., bvh=)``), and the functional chain with the same poses.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st

import cgaskin
from cgaskin import InvalidInputError, MissesMeshError, Surgery, TearPathError
from cgaskin.surgery.bvh import TriangleBVH, _first_hit
from cgaskin.surgery.bone_influences import tree_influences, weight_summary
from cgaskin.surgery.posed_bounds import PosedScratch, pose_region

from tests.helpers.tear_checks import diagonal, strokes, surface
from tests.surgery.test_session import assert_same_boundary, assert_same_mesh

SETTINGS = dict(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
                deadline=None)
STROKE_ERRORS = (TearPathError, MissesMeshError, InvalidInputError)


@st.composite
def poses(draw, rig):
    """A clip frame at any time (or the rest pose), then a random rotation, dilation and translation of
    random joints: what a user plays and edits."""
    names = rig.skeleton.names
    pose = rig.pose(0, draw(st.floats(-0.1, 1.1)) * rig.clips[0].duration) if rig.clips and draw(st.booleans()) \
        else rig.rest_pose()
    for _ in range(draw(st.integers(0, 2))):
        joint = draw(st.sampled_from(names))
        edit = draw(st.sampled_from(["rotate", "dilate", "translate"]))
        if edit == "rotate":
            axis = draw(st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 0.1))
            pose = pose.rotate(joint, axis, draw(st.floats(-2.0, 2.0)))
        elif edit == "dilate":
            pose = pose.dilate(joint, draw(st.floats(0.5, 2.0)))
        else:
            shift = np.array(draw(st.tuples(*[st.floats(-0.2, 0.2)] * 3)))
            pose = pose.translate(joint, shift * diagonal(rig.vertices))
    return pose


def posed_tree(rig, pose):
    """(posed BVHArrays, Posing) of rig's rest BVH in pose, nothing posed yet."""
    bvh = TriangleBVH(rig.vertices, rig.faces)
    tree = tuple(bvh._arrays)
    masks = tree_influences(*(tree[k] for k in (2, 3, 4, 5, 6, 8)), np.ascontiguousarray(rig.joints, np.int64),
                       np.ascontiguousarray(rig.weights, np.float64), len(tree[0]), rig.skeleton.n_bones, len(tree[0]))
    return PosedScratch().view(tree, len(tree[0]), masks, np.ascontiguousarray(rig.vertices, np.float64),
                               np.ascontiguousarray(rig.joints, np.int64),
                               np.ascontiguousarray(rig.weights, np.float64),
                               pose.bone_affines(), weight_summary(np.ascontiguousarray(rig.joints, np.int64),
                                                                 np.ascontiguousarray(rig.weights, np.float64),
                                                                 rig.skeleton.n_bones)[1])


@settings(max_examples=15, **SETTINGS)
@given(data=st.data())
def test_posed_boxes_hold_every_skinned_vertex(tear_model, data):
    """Every node's bone-carried box holds the skinned corners of every face under it, in any pose;
    the posed positions are ``skin``'s, bit for bit."""
    _, rig = tear_model
    pose = data.draw(poses(rig))
    bvh, posing = posed_tree(rig, pose)
    pose_region(bvh, posing, np.zeros(4), np.full(3, -np.inf), np.full(3, np.inf), np.inf)
    lo, hi, left, right, start, count, order, positions, faces = bvh
    skinned = cgaskin.skin(rig, pose)
    used = np.unique(faces)
    np.testing.assert_array_equal(positions[used], skinned[used])
    parent = np.full(len(left), -1)
    inner = np.flatnonzero(left >= 0)
    parent[left[inner]], parent[right[inner]] = inner, inner
    for leaf in np.flatnonzero(left < 0):          # the leaf's box and every ancestor's hold its corners
        corners = skinned[faces[order[start[leaf]:start[leaf] + count[leaf]]]].reshape(-1, 3)
        node = leaf
        while node >= 0:
            assert (corners >= lo[node]).all() and (corners <= hi[node]).all(), (leaf, node)
            node = parent[node]


@settings(max_examples=25, **SETTINGS)
@given(data=st.data())
def test_posed_first_hit_is_the_skinned_surfaces(tear_model, data):
    """A segment posed where it reaches meets the posed tree where it meets a BVH of the whole skinned
    surface: the same face at the same parameter (never a face missed)."""
    _, rig = tear_model
    pose = data.draw(poses(rig))
    skinned = cgaskin.skin(rig, pose)
    brute = TriangleBVH(skinned, rig.faces)
    bvh, posing = posed_tree(rig, pose)
    f = data.draw(st.integers(0, rig.n_faces - 1))
    w = np.array(data.draw(st.tuples(*[st.floats(0.01, 1.0)] * 3)))
    target = (w / w.sum()) @ skinned[rig.faces[f]]
    direction = np.array(data.draw(st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda d: np.linalg.norm(d) > 0.1)))
    a = target + 0.3 * diagonal(skinned) * direction / np.linalg.norm(direction)
    b = target - 0.05 * diagonal(skinned) * direction / np.linalg.norm(direction)
    pose_region(bvh, posing, np.empty(0), a, b, 0.0)
    face, t = _first_hit(bvh, a, b)
    expected = brute.first_hit(a, b)
    event("hits" if expected[0] >= 0 else "misses (the face is degenerate in this pose)")
    assert int(face) == expected[0] and (expected[0] < 0 or float(t) == expected[1])


def test_a_posed_stroke_equals_a_stroke_on_the_skinned_surface(tear_model):
    """The old way built a BVH of the whole skinned surface per pose: a stroke posed where it reaches
    gives the same rig (faces, positions, weights)."""
    name, rig = tear_model
    pose = rig.pose(0, 0.3 * rig.clips[0].duration) if rig.clips else rig.rest_pose().dilate(1, 1.3)
    points = surface(rig, pose)
    made = 0
    for seed in range(8):
        rng = np.random.default_rng(seed)
        f = rng.integers(rig.n_faces)
        p0 = points[rig.faces[f]].mean(axis=0)
        n = np.cross(*(points[rig.faces[f][1:]] - points[rig.faces[f][0]]))
        n /= np.linalg.norm(n)
        side = np.cross(n, rng.normal(size=3))
        side *= 0.01 * diagonal(points) / np.linalg.norm(side)
        h = 0.02 * diagonal(points) * n
        blades = (np.array([p0 + h, p0 - h]), np.array([p0 + side + h, p0 + side - h]))
        try:
            expected = cgaskin.tear_stroke(rig, *blades, pose=pose, bvh=TriangleBVH(points, rig.faces))
        except STROKE_ERRORS:
            continue
        got = cgaskin.tear_stroke(rig, *blades, pose=pose)
        assert_same_mesh(got.rig, expected.rig, diagonal(points))
        np.testing.assert_array_equal(got.points, expected.points)
        made += 1
    assert made >= 3, name


@settings(max_examples=10, **SETTINGS)
@given(data=st.data())
def test_a_session_in_many_poses_equals_the_functional_chain(tear_model, data):
    """Each operation in a pose of its own (a playing model): the session follows the functional chain
    with the same poses, undo included; its bone influences stay those of its tree built anew."""
    _, rig = tear_model
    session, chain = Surgery(rig), [rig]
    for _ in range(data.draw(st.integers(1, 5), label="operations")):
        if len(chain) > 1 and data.draw(st.integers(0, 4)) == 0:
            session.undo()
            chain.pop()
            continue
        pose = data.draw(poses(rig))
        points = surface(chain[-1], pose)
        blades = data.draw(strokes(chain[-1], points))
        opening = data.draw(st.sampled_from([0.0, 0.003])) * diagonal(points)
        try:
            expected = cgaskin.tear(chain[-1], *blades, pose=pose, opening=opening)
        except STROKE_ERRORS as error:
            event(f"a stroke raises {type(error).__name__}")
            before = session.rig
            with pytest.raises(type(error)):
                session.tear(*blades, pose=pose, opening=opening)
            assert session.rig is before
            continue
        session.tear(*blades, pose=pose, opening=opening)
        event("a stroke tears")
        chain.append(expected)
        assert_same_mesh(session.rig, chain[-1], diagonal(points))
        assert_same_boundary(session, chain[-1])
    tree = session._bvh.arrays
    fresh = tree_influences(*(tree[k] for k in (2, 3, 4, 5, 6, 8)), session.joints, session.weights,
                       session._bvh.n_nodes, rig.skeleton.n_bones, len(tree[0]))
    kept = session._influences.influences(session.joints, session.weights)
    for got, expected in zip(kept, fresh):
        np.testing.assert_array_equal(got[:session._bvh.n_nodes], expected[:session._bvh.n_nodes])


def test_strokes_along_a_playing_capsule():
    """An incision made while the capsule plays ``wave``: stroke k in frame k starts where the last one
    ended (that vertex skinned in this frame) and runs along the forearm; each stroke continues the slit,
    the session equals the chain, and the torn rig plays."""
    rig = cgaskin.capsule_arm()
    session, current, end = Surgery(rig), rig, None
    for k in range(10):
        pose = rig.pose("wave", 0.1 * k)
        forearm = pose.bone_affines()[1].reshape(3, 4)
        up, along = forearm[:, 1], forearm[:, 0]
        start = forearm @ [1.3, 0.25, 0.013, 1.0] if end is None else cgaskin.skin(current, pose)[end]
        blades = (np.array([start + 0.2 * up, start - 0.2 * up]),
                  np.array([start + 0.02 * along + 0.2 * up, start + 0.02 * along - 0.2 * up]))
        session.tear(*blades, pose=pose)
        stroke = cgaskin.tear_stroke(current, *blades, pose=pose)
        if end is not None:
            assert stroke.split[0], "each stroke continues the slit"
        current, end = stroke.rig, stroke.side_a[-1]
    assert_same_mesh(session.rig, current, 1.0)
    assert session.n_faces > rig.n_faces + 20
    assert np.isfinite(cgaskin.skin(session.rig, rig.pose("wave", 0.77))).all()


def test_bad_poses_leave_the_session_unchanged():
    """A pose of another skeleton, not a pose, or one whose transforms overflow: a clear error, and the
    session as it was."""
    rig = cgaskin.capsule_arm()
    session = Surgery(rig)
    before = session.rig
    blades = (np.array([[1.0, 0.4, 0.01], [1.0, 0.0, 0.01]]), np.array([[1.05, 0.4, 0.01], [1.05, 0.0, 0.01]]))
    with pytest.raises(InvalidInputError, match="pose"):
        session.tear(*blades, pose="wave")
    with pytest.raises(InvalidInputError, match="another skeleton"):
        session.tear(*blades, pose=cgaskin.capsule_arm(n_joints=4).rest_pose())
    with pytest.raises(InvalidInputError, match="another skeleton"):
        session.cut([1, 0, 0], [1, 0, 0], pose=cgaskin.capsule_arm(n_joints=4).rest_pose())
    with np.errstate(over="ignore"):
        huge = rig.rest_pose().translate(0, [1e200, 0, 0]).dilate(0, 1e12).dilate(1, 1e12).dilate(2, 1e12)
    with pytest.raises(InvalidInputError, match="overflow"):
        session.tear(*blades, pose=huge)
    assert session.rig is before and session.n_operations == 0
