"""The procedural capsule arm: a closed, consistently oriented mesh with a valid skin and clip."""
import numpy as np
import pytest

from cgaskin import Rig, check_mesh
from cgaskin.errors import InvalidInputError
from cgaskin.rigs.procedural import capsule_arm
from cgaskin import baselines as B


def _edge_faces(faces):
    """Directed edge -> number of faces using it in that direction."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    keys, counts = np.unique(directed, axis=0, return_counts=True)
    return {tuple(k): c for k, c in zip(keys, counts)}


def _signed_volume(vertices, faces):
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


RIGS = [dict(), dict(n_joints=1), dict(n_joints=2, rings_per_segment=1, segments_around=3),
        dict(n_joints=5, length=10.0, radius=0.1, rings_per_segment=3, segments_around=7)]


@pytest.fixture(scope="module")
def arm():
    return capsule_arm()


@pytest.mark.parametrize("kwargs", RIGS)
def test_closed_manifold_outward(kwargs):
    rig = capsule_arm(**kwargs)
    faces = rig.faces
    assert faces.dtype == np.int64 and faces.shape[1] == 3
    assert faces.min() == 0 and faces.max() == rig.n_vertices - 1      # every vertex used
    assert np.all((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0]))
    directed = _edge_faces(faces)
    # Watertight and consistently oriented: each directed edge is used once, and its reverse once.
    assert all(c == 1 for c in directed.values())
    assert all((b, a) in directed for a, b in directed)
    # Euler characteristic of a sphere
    assert rig.n_vertices - len(directed) // 2 + rig.n_faces == 2
    # Outward: positive volume close to the analytic capsule's (the mesh is inscribed, so smaller)
    length = kwargs.get("length", 3.0)
    radius = kwargs.get("radius", 0.25)
    exact = np.pi * radius ** 2 * length + 4 / 3 * np.pi * radius ** 3
    volume = _signed_volume(rig.vertices, faces)
    assert 0 < volume <= exact
    if kwargs.get("segments_around", 16) >= 16:
        assert volume > 0.95 * exact


def test_every_face_faces_outward(arm):
    """Each face normal agrees with the vertex normals (outward) at its corners."""
    v, f = arm.vertices, arm.faces
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    corner_normals = arm.attributes["NORMAL"][f].sum(axis=1)
    assert np.all(np.einsum("ij,ij->i", n, corner_normals) > 0)


def test_geometry_and_normals(arm):
    v, normals = arm.vertices, arm.attributes["NORMAL"]
    assert v.dtype == np.float64 and v.shape == (arm.n_vertices, 3)
    assert 500 <= arm.n_vertices <= 3000      # small enough for a fast demo
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-15)
    # every vertex lies on the capsule surface: distance radius from the segment [0, 3] on the x axis
    closest = np.stack([np.clip(v[:, 0], 0.0, 3.0), np.zeros(len(v)), np.zeros(len(v))], axis=1)
    assert np.allclose(np.linalg.norm(v - closest, axis=1), 0.25, atol=1e-14)
    # and the normal points away from the axis segment
    assert np.allclose(normals * 0.25, v - closest, atol=1e-14)
    assert v[:, 0].min() == pytest.approx(-0.25) and v[:, 0].max() == pytest.approx(3.25)


@pytest.mark.parametrize("kwargs", RIGS)
def test_weights_valid_and_smooth(kwargs):
    rig = capsule_arm(**kwargs)
    n_joints = kwargs.get("n_joints", 3)
    j, w = rig.joints, rig.weights
    assert j.shape == w.shape == (rig.n_vertices, 4)
    assert j.dtype == np.int64 and w.dtype == np.float64
    assert np.all(w >= 0) and np.allclose(w.sum(axis=1), 1.0, atol=1e-15)
    assert np.all((j >= 0) & (j < n_joints))
    assert np.all((w > 0).sum(axis=1) <= 2)
    # influences are neighbours in the chain
    both = (w[:, 0] > 0) & (w[:, 1] > 0)
    assert np.all(j[both, 1] - j[both, 0] == 1)
    # the blend varies smoothly along the axis: weight of the second bone is monotone in x
    if n_joints > 1:
        length = kwargs.get("length", 3.0)
        spacing = length / n_joints
        x = rig.vertices[:, 0]
        expected_bone = np.clip(np.floor(x / spacing), 0, n_joints - 1)
        dominant = np.take_along_axis(j, np.argmax(w, axis=1)[:, None], 1)[:, 0]
        inside = np.abs(x / spacing - np.round(x / spacing)) > 0.01   # away from joints (ties)
        assert np.all(dominant[inside] == expected_bone[inside])


def test_validates_with_check_mesh(arm):
    v, f, j, w = check_mesh(arm.vertices, arm.faces, arm.joints, arm.weights,
                            n_bones=arm.skeleton.n_bones, source="capsule_arm")
    assert np.array_equal(v, arm.vertices) and np.array_equal(f, arm.faces)
    assert np.array_equal(j, arm.joints) and np.array_equal(w, arm.weights)


def test_skeleton(arm):
    sk = arm.skeleton
    assert sk.names == ["shoulder", "elbow", "wrist"]
    assert list(sk.parents) == [-1, 0, 1]
    assert list(sk.bone_nodes) == [0, 1, 2]
    assert capsule_arm(n_joints=4).skeleton.names == ["joint0", "joint1", "joint2", "joint3"]
    local = B.trs_matrix(sk.rest_translations, sk.rest_rotations, sk.rest_scales)
    assert np.allclose(local, sk.rest_matrices, atol=0)
    glob = B.global_matrices(sk.parents, sk.rest_matrices)
    assert np.allclose(glob[:, :3, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]], atol=1e-15)
    # inverse bind = inverse of the global bind matrix, and rest pose = bind pose
    assert np.allclose(glob @ sk.inverse_bind, np.eye(4), atol=1e-15)
    skinned = B.lbs_matrices(arm.vertices, arm.joints, arm.weights, glob[sk.bone_nodes] @ sk.inverse_bind)
    assert np.allclose(skinned, arm.vertices, atol=1e-15)


def _pose(rig, clip, t):
    """Local matrices of the clip at time t (LINEAR keys: normalised lerp is enough for the check)."""
    sk = rig.skeleton
    rot = sk.rest_rotations.copy()
    for ch in clip.channels:
        k = min(max(np.searchsorted(ch.times, t, side="right") - 1, 0), len(ch.times) - 2)
        u = np.clip((t - ch.times[k]) / (ch.times[k + 1] - ch.times[k]), 0, 1)
        q = (1 - u) * ch.values[k] + u * ch.values[k + 1]
        rot[ch.node] = q / np.linalg.norm(q)
    return B.global_matrices(sk.parents, B.trs_matrix(sk.rest_translations, rot, sk.rest_scales))


def test_wave_clip(arm):
    (clip,) = arm.clips
    assert clip.name == "wave" and clip.duration == 2.0
    assert {ch.node for ch in clip.channels} == {0, 1, 2}
    for ch in clip.channels:
        assert ch.path == "rotation" and ch.interpolation == "LINEAR"
        assert ch.values.shape == (len(ch.times), 4) and len(ch.times) >= 3
        assert np.all(np.diff(ch.times) > 0)
        assert np.allclose(np.linalg.norm(ch.values, axis=1), 1.0, atol=1e-15)
        assert np.all(np.einsum("ij,ij->i", ch.values[1:], ch.values[:-1]) > 0)   # no sign flips
        assert np.allclose(ch.values[0], [0, 0, 0, 1]) and np.allclose(ch.values[-1], [0, 0, 0, 1])
    elbow = next(ch for ch in clip.channels if ch.node == 1)
    assert np.ptp(elbow.values[:, 2]) > 0.5      # a real bend about z
    # mid-clip the arm is bent: the tip moves, the skinned mesh stays finite and connected
    sk = arm.skeleton
    glob = _pose(arm, clip, 1.0)
    posed = B.lbs_matrices(arm.vertices, arm.joints, arm.weights, glob[sk.bone_nodes] @ sk.inverse_bind)
    assert np.all(np.isfinite(posed))
    assert np.abs(posed - arm.vertices).max() > 1.0
    edges = np.concatenate([arm.faces[:, [0, 1]], arm.faces[:, [1, 2]], arm.faces[:, [2, 0]]])
    lengths = np.linalg.norm(posed[edges[:, 0]] - posed[edges[:, 1]], axis=1)
    assert lengths.max() < 3 * np.linalg.norm(arm.vertices[edges[:, 0]] - arm.vertices[edges[:, 1]], axis=1).max()


def test_deterministic():
    a, b = capsule_arm(), capsule_arm()
    for name in ("vertices", "faces", "joints", "weights"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.attributes["NORMAL"], b.attributes["NORMAL"])
    for ca, cb in zip(a.clips[0].channels, b.clips[0].channels):
        assert np.array_equal(ca.values, cb.values) and np.array_equal(ca.times, cb.times)
    assert isinstance(a, Rig) and a.name == "capsule_arm"


@pytest.mark.parametrize("kwargs", [dict(n_joints=0), dict(n_joints=2.5), dict(length=0), dict(radius=-1),
                                    dict(radius=float("nan")), dict(rings_per_segment=0),
                                    dict(segments_around=2), dict(n_joints=True)])
def test_bad_arguments(kwargs):
    with pytest.raises(InvalidInputError):
        capsule_arm(**kwargs)
