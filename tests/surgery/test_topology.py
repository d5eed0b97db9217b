"""The welded topology that cut and tear run on (cgaskin.surgery.topology).
"""
import dataclasses

import numpy as np
import pytest

import cgaskin
from cgaskin import capsule_arm, rig_topology
from cgaskin.errors import InvalidInputError
from cgaskin.surgery.topology import boundary_flags, clear_topology_cache, topology

from tests.helpers.cut_checks import model, orientation_defects


def test_topology_welds_attribute_seams(models_dir):
    fox = model(models_dir, "Fox.glb")
    topo = topology(fox.vertices, fox.faces)
    assert len(np.unique(fox.faces)) == 3 * len(fox.faces)          # fully unindexed
    assert topo.n_welded == len(np.unique(fox.vertices, axis=0))
    assert (topo.edge_face_counts == 2).all()                       # closed once welded
    assert orientation_defects(topo) == 0
    assert np.array_equal(fox.vertices[topo.representative[topo.welded]], fox.vertices)
    arm = model(models_dir, "Arm5.glb")
    topo = topology(arm.vertices, arm.faces)
    assert len(topo.boundary_edges) == 37
    assert len(topo.vertex_edges) > len(topo.edges)                 # seams: more vertex edges


def test_topology_structure():
    rig = capsule_arm()
    topo = topology(rig.vertices, rig.faces)
    m = len(rig.faces)
    assert topo.n_edges == 3 * m // 2 and (topo.edge_face_counts == 2).all()
    # incidence lists agree with face_edges
    for e in range(0, topo.n_edges, 97):
        faces = topo.edge_faces(e)
        for f in faces:
            assert e in topo.face_edges[f]
    # edges are the welded corner pairs
    f, k = topo.edge_face_faces, topo.edge_face_corners.astype(np.int64)
    pairs = np.sort(np.stack([topo.faces[f, k], topo.faces[f, (k + 1) % 3]], axis=1), axis=1)
    assert np.array_equal(pairs, topo.edges[np.repeat(np.arange(topo.n_edges), topo.edge_face_counts)])
    assert np.array_equal(topo.find_edges(topo.edges[:, 1], topo.edges[:, 0]), np.arange(topo.n_edges))
    assert topo.find_edges([0], [len(rig.vertices) - 1])[0] == -1
    # -0.0 and 0.0 weld
    v = np.array([[0.0, 0, 0], [-0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    t = topology(v, np.array([[0, 2, 4], [1, 4, 3]]))
    assert t.welded[0] == t.welded[1] and t.n_welded == 4 and t.n_edges == 5
    assert len(t.boundary_edges) == 4 and len(t.vertex_edges) == 6
    assert t.boundary_loops() == [[0, 1, 3, 2]]          # welded ids of vertices 0, 2, 4, 3


def test_topology_boundary_loops(models_dir):
    plane = model(models_dir, "PlaneWith3Bones.glb")
    loops = topology(plane.vertices, plane.faces).boundary_loops()
    assert [len(loop) for loop in loops] == [16]


@pytest.mark.parametrize("name", ["PlaneWith3Bones.glb", "Fox.glb", "labelled capsule", "torn capsule"])
def test_boundary_flags_are_the_topologys(models_dir, name):
    """``boundary_flags`` (the tear's per-vertex boundary, without the whole topology) marks exactly
    the ends of the topology's boundary edges, with and without tear labels."""
    labels = None
    if name == "labelled capsule":           # labels that split nothing (one vertex per position)
        rig = capsule_arm()
        labels = np.random.default_rng(3).integers(-2, 3, rig.n_vertices)
    elif name == "torn capsule":
        rig = capsule_arm()
        rig = cgaskin.tear(rig, [[0.4, 0.35, 0.02], [0.4, 0.0, 0.02]], [[0.6, 0.35, 0.02], [0.6, 0.0, 0.02]])
        labels = np.rint(rig.attributes["_TEAR"][:, 0]).astype(np.int64)
    else:
        rig = model(models_dir, name)
    vertices, faces = np.asarray(rig.vertices, float), np.asarray(rig.faces, np.int64)
    topo = topology(vertices, faces, labels)
    expected = np.zeros(topo.n_welded, bool)
    expected[topo.edges[topo.boundary_edges].reshape(-1)] = True
    flags = boundary_flags(vertices, faces, labels)
    np.testing.assert_array_equal(flags, expected[topo.welded])
    if name in ("PlaneWith3Bones.glb", "torn capsule"):       # open meshes: something to find
        assert flags.any()


def test_rig_topology_is_cached():
    rig = capsule_arm()
    first = rig_topology(rig)
    assert rig_topology(rig) is first
    clear_topology_cache()
    assert rig_topology(rig) is not first


def test_topology_rejects_bad_arrays():
    with pytest.raises(InvalidInputError):
        topology(np.zeros((3, 2)), np.zeros((1, 3), np.int64))
    with pytest.raises(InvalidInputError):
        topology(np.zeros((3, 3)), np.array([[0, 1, 3]]))
    with pytest.raises(InvalidInputError):
        topology(np.full((3, 3), np.nan), np.array([[0, 1, 2]]))
    with pytest.raises(InvalidInputError, match="labels"):
        topology(np.eye(3), np.array([[0, 1, 2]]), labels=[0, 1])
    with pytest.raises(InvalidInputError, match="labels"):
        topology(np.eye(3), np.array([[0, 1, 2]]), labels=[0.5, 1.0, 2.0])


def test_tear_labels_of_any_sign_never_weld_distant_vertices():
    """Issue 10, item 6: negative labels made the key welded * (max + 1) + label collide."""
    from cgaskin.surgery.tear import TEAR_LABEL, tear_topology
    rig = cgaskin.capsule_arm()
    by_position = cgaskin.rig_topology(rig)
    labels = np.random.default_rng(5).integers(-5, 6, by_position.n_welded)[by_position.welded]
    labelled = dataclasses.replace(rig, attributes={**rig.attributes,
                                                    TEAR_LABEL: labels[:, None].astype(float)})
    topo = tear_topology(labelled)
    assert topo.n_welded == by_position.n_welded
    spread = np.zeros(topo.n_welded)
    offsets = np.linalg.norm(rig.vertices - rig.vertices[topo.representative[topo.welded]], axis=1)
    np.maximum.at(spread, topo.welded, offsets)
    assert spread.max() == 0.0


def test_tear_labels_must_be_whole_numbers():
    from cgaskin.surgery.tear import TEAR_LABEL
    rig = cgaskin.capsule_arm()
    labels = np.zeros((rig.n_vertices, 1))
    labels[7] = 0.5
    labelled = dataclasses.replace(rig, attributes={**rig.attributes, TEAR_LABEL: labels})
    with pytest.raises(cgaskin.InvalidInputError, match="whole numbers.*vertex 7"):
        cgaskin.tear(labelled, ([0.6, 0.5, 0.0], [0.6, 0.0, 0.0]), ([0.9, 0.5, 0.0], [0.9, 0.0, 0.0]))
