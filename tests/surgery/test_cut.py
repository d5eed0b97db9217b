"""Plane cuts (cgaskin.cut), fixed cases: planes through vertices and faces, seams, planes that miss,
posed cuts, the caller's rig left alone, export of the halves, bad input.
"""
import warnings

import numpy as np
import pytest

import cgaskin
from cgaskin import PlaneMissesMeshWarning, Rig, capsule_arm, cut, cut_details
from cgaskin.errors import InvalidInputError

from tests.helpers.cut_checks import MODELS, chain_skeleton, check_cut, diagonal, model


# ---- specific cases -----------------------------------------------------------------------------------
def test_plane_through_a_ring_of_vertices_makes_no_new_vertex():
    rig = capsule_arm()
    ring_x = 0.25                                  # a ring of the cylinder (x = k * 3 / 36)
    assert np.count_nonzero(rig.vertices[:, 0] == ring_x) == 16
    result = cut_details(rig, [1, 0, 0], [ring_x, 0, 0], cap=True)
    assert len(result.edge_t) == 0
    a, b = result.positive, result.negative
    ring = np.flatnonzero(rig.vertices[:, 0] == ring_x)
    for h, src in zip((a, b), result.sources):
        assert set(ring) <= set(src[src >= 0].tolist())        # on-plane vertices in both halves
        assert len(np.unique(src[src >= 0])) == np.count_nonzero(src >= 0)  # no duplicates
    assert len(a.faces) + len(b.faces) - 2 * 14 == len(rig.faces)  # 16-gon caps: 14 triangles each
    check_cut(rig, result, closed=True, capped=True)


def test_seam_copies_of_a_crossed_edge_share_one_position():
    # every face of the capsule gets private vertices (like Fox): all edges are seams
    base = capsule_arm()
    f = base.faces
    flat = f.reshape(-1)
    rig = Rig(vertices=base.vertices[flat], faces=np.arange(len(flat)).reshape(-1, 3), joints=base.joints[flat],
              weights=base.weights[flat], skeleton=base.skeleton, clips=base.clips,
              attributes={"NORMAL": base.attributes["NORMAL"][flat],
                          "TEXCOORD_0": np.random.default_rng(0).random((len(flat), 2))})
    result = cut_details(rig, [1, 0.2, 0.1], [1.3, 0.01, 0.02], cap=True)
    # two faces on each crossed edge: two new vertices per welded edge, at one position
    assert len(result.edge_t) == 2 * len(np.unique(result.new_positions, axis=0))
    check_cut(rig, result, closed=True, capped=True)


def test_plane_touching_one_vertex_misses():
    rig = capsule_arm()
    pole = rig.vertices[:, 0].argmin()
    with pytest.warns(PlaneMissesMeshWarning):
        a, b = cut(rig, [1, 0, 0], rig.vertices[pole])
    assert len(b.faces) == 0 and np.array_equal(a.faces, rig.faces)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_missing_plane_returns_whole_and_empty(sign):
    rig = capsule_arm()
    with pytest.warns(PlaneMissesMeshWarning, match="does not cross"):
        a, b = cut(rig, [sign, 0, 0], [-10.0, 0, 0])
    whole, empty = (a, b) if sign > 0 else (b, a)
    assert np.array_equal(whole.vertices, rig.vertices) and whole.vertices is not rig.vertices
    assert np.array_equal(whole.faces, rig.faces) and np.array_equal(whole.weights, rig.weights)
    assert whole.attributes["NORMAL"] is not rig.attributes["NORMAL"]
    assert empty.vertices.shape == (0, 3) and empty.faces.shape == (0, 3)
    assert empty.joints.shape == (0, 4) and empty.weights.shape == (0, 4)
    assert empty.attributes["NORMAL"].shape == (0, 3)
    assert whole.skeleton is rig.skeleton and empty.skeleton is rig.skeleton
    assert [c.name for c in empty.clips] == ["wave"]


def test_face_in_the_plane_goes_to_the_side_it_bounds():
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box()                   # the unit cube around the origin
    rig = Rig(vertices=np.asarray(box.vertices), faces=np.asarray(box.faces, np.int64),
              joints=np.zeros((8, 4), np.int64), weights=np.tile([1.0, 0, 0, 0], (8, 1)),
              skeleton=chain_skeleton(1, np.random.default_rng(0)))
    # the plane of the top face: the whole cube is below it (on the negative side)
    with pytest.warns(PlaneMissesMeshWarning):
        a, b = cut(rig, [0, 0, 1], [0, 0, 0.5])
    assert len(a.faces) == 0 and len(b.faces) == 12


def test_caller_rig_is_not_modified():
    rig = capsule_arm()
    for arr in (rig.vertices, rig.faces, rig.joints, rig.weights, rig.attributes["NORMAL"]):
        arr.flags.writeable = False                # any write would raise
    before = {k: np.array(v) for k, v in (("v", rig.vertices), ("f", rig.faces), ("w", rig.weights))}
    pose = rig.pose("wave", 0.8)
    a, b = cut(rig, [1, 1, 0], [1.5, 0, 0], pose=pose, cap=True)
    assert np.array_equal(rig.vertices, before["v"]) and np.array_equal(rig.faces, before["f"])
    assert np.array_equal(rig.weights, before["w"])
    # a new rig of its own arrays, read-only like every rig's (issue 22)
    assert not a.vertices.flags.writeable and not np.shares_memory(a.vertices, rig.vertices)


def test_posed_cut_places_new_vertices_on_the_posed_plane():
    rig = capsule_arm()
    pose = rig.pose("wave", 1.0)                   # elbow bent 90 degrees
    posed = cgaskin.skin(rig, pose)
    normal, point = np.array([1.0, 1.0, 0.0]), posed.mean(axis=0)
    result = cut_details(rig, normal, point, pose=pose)
    for h, first in zip((result.positive, result.negative), result.first_new):
        new = cgaskin.skin(h, pose)[first:]
        assert np.abs((new - point) @ normal / np.linalg.norm(normal)).max() <= 1e-12 * diagonal(posed)
    # the rest positions are not the rest-space edge points: the cut happened in the pose
    lerp = (rig.vertices[result.edge_vertices[:, 0]] * (1 - result.edge_t)[:, None]
            + rig.vertices[result.edge_vertices[:, 1]] * result.edge_t[:, None])
    first = result.first_new[0]
    assert np.abs(result.positive.vertices[first:] - lerp).max() > 1e-6


@pytest.mark.parametrize("name", MODELS + ["capsule"])
def test_halves_export_and_reload(models_dir, tmp_path, name):
    export = pytest.importorskip("cgaskin.rigs.export")
    rig = model(models_dir, name)
    a, b = cut(rig, [1, 0.2, 0.1], rig.vertices.mean(axis=0), cap=True)
    for h, label in ((a, "a"), (b, "b")):
        path = export.save_gltf(h, tmp_path / f"{label}.glb")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            back = cgaskin.load(path)
        assert np.array_equal(back.faces, h.faces)
        assert np.allclose(back.vertices, h.vertices, rtol=1e-6, atol=1e-6 * diagonal(h.vertices))
        assert np.allclose(back.weights, h.weights, atol=1e-6)
        assert back.skeleton.n_bones == rig.skeleton.n_bones and len(back.clips) == len(rig.clips)


# ---- bad input ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("normal,point", [
    ([0, 0, 0], [0, 0, 0]), ([np.nan, 0, 1], [0, 0, 0]), ([1, 0, 0], [0, np.inf, 0]), ([1, 0], [0, 0, 0]),
    ([1, 0, 0], [[0, 0, 0]]), ("up", [0, 0, 0]), ([1, 0, 0], None)])
def test_bad_planes(normal, point):
    with pytest.raises(InvalidInputError):
        cut(capsule_arm(), normal, point)


def test_bad_rigs_and_poses(models_dir):
    rig = capsule_arm()
    with pytest.raises(InvalidInputError, match="another skeleton"):
        cut(rig, [1, 0, 0], [1, 0, 0], pose=model(models_dir, "Fox.glb").rest_pose())
    with pytest.raises(InvalidInputError):
        cut(rig, [1, 0, 0], [1, 0, 0], pose="wave")
    with pytest.raises(InvalidInputError):
        cut(rig.vertices, [1, 0, 0], [1, 0, 0])
    with pytest.raises(InvalidInputError):
        cut(rig, [1, 0, 0], [1, 0, 0], cap="yes")
    with pytest.raises(InvalidInputError, match="no faces"):
        cut(rig.with_mesh(rig.vertices, np.empty((0, 3), np.int64), rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    nan = rig.vertices.copy()
    nan[3, 1] = np.nan
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(nan, rig.faces, rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    out_of_range = rig.faces.copy()
    out_of_range[0, 0] = len(rig.vertices)
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, out_of_range, rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    bad_joints = rig.joints.copy()
    bad_joints[0, 0] = 99
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, rig.faces, bad_joints, rig.weights), [1, 0, 0], [1, 0, 0])
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, rig.faces, rig.joints, rig.weights[:, :3]), [1, 0, 0], [1, 0, 0])


# ---- other input types ---------------------------------------------------------------------------------
def test_other_dtypes_are_accepted():
    base = capsule_arm()
    rig = Rig(vertices=base.vertices.astype(np.float32), faces=base.faces.astype(np.int32),
              joints=base.joints.astype(np.uint8), weights=base.weights.astype(np.float32),
              skeleton=base.skeleton, attributes={"NORMAL": base.attributes["NORMAL"].astype(np.float32),
                                                  "_ID": np.arange(len(base.vertices))})
    result = cut_details(rig, [1, 0.2, 0], [1.2, 0, 0], cap=True)
    a = result.positive
    assert a.vertices.dtype == np.float64 and a.joints.dtype == np.int64 and a.weights.dtype == np.float64
    assert a.attributes["NORMAL"].dtype == np.float32 and a.attributes["_ID"].shape == (len(a.vertices),)
    old = result.sources[0] >= 0
    assert np.array_equal(a.attributes["_ID"][old], result.sources[0][old])


@pytest.mark.parametrize("up", [1.0, -1.0])
def test_face_in_the_plane_is_kept_by_the_side_below_its_normal(up):
    # face 0 lies in z = 0 with normal +z; face 1 rises to z = 1 from its edge
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]])
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    rig = Rig(vertices=vertices, faces=faces, joints=np.zeros((4, 4), np.int64),
              weights=np.tile([1.0, 0, 0, 0], (4, 1)), skeleton=chain_skeleton(1, np.random.default_rng(0)))
    above, below = cut(rig, [0, 0, up], [0, 0, 0])
    if up < 0:
        above, below = below, above
    assert np.array_equal(below.faces, [[0, 1, 2]]) and np.array_equal(below.vertices, vertices[:3])
    assert len(above.faces) == 1 and np.array_equal(above.vertices, vertices[1:])
