"""glTF loader on synthetic files, one spec feature at a time: containers, component types, strides,
sparse accessors, padded matrices, strips and fans, merged primitives and skins, matrix nodes,
animations.
"""
import numpy as np
import pytest

from cgaskin.rigs.gltf import load_gltf, matrix_to_trs, trs_to_matrix

from tests.helpers.gltf_files import QUAD_VERTICES, Gltf, assert_valid_rig, load_quietly


@pytest.mark.parametrize("name, kind", [("q.glb", None), ("q.gltf", None), ("q.gltf", "external")])
def test_synthetic_quad_in_every_container(tmp_path, name, kind):
    rig = load_gltf(Gltf.quad().write(tmp_path / name, kind))
    assert_valid_rig(rig)
    assert np.array_equal(rig.vertices, QUAD_VERTICES)
    assert rig.faces.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert rig.joints.tolist() == [[0, 0, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0]]
    assert rig.weights.tolist() == [[1, 0, 0, 0], [0.75, 0.25, 0, 0], [0.5, 0.5, 0, 0], [1, 0, 0, 0]]
    sk = rig.skeleton
    # the non-joint root is part of the skeleton; the mesh node is not
    assert sk.names == ["Armature", "A", "B"] and sk.parents.tolist() == [-1, 0, 1]
    assert sk.bone_nodes.tolist() == [1, 2]
    assert np.array_equal(sk.inverse_bind, np.broadcast_to(np.eye(4), (2, 4, 4)))  # default: identity
    assert sk.rest_translations.tolist() == [[0, 0, 1], [0, 0, 0], [0.5, 0, 0]]
    assert rig.clips == [] and rig.attributes == {}


@pytest.mark.parametrize("positions_type", [5126, 5120, 5121, 5122, 5123])
@pytest.mark.parametrize("index_type", [5121, 5123, 5125])
def test_component_types_of_positions_and_indices(tmp_path, positions_type, index_type):
    rig = load_gltf(Gltf.quad(positions_type=positions_type, index_type=index_type).write(tmp_path / "q.glb"))
    if positions_type == 5126:
        assert np.array_equal(rig.vertices, QUAD_VERTICES)
    else:
        scale = {5120: 127, 5121: 255, 5122: 32767, 5123: 65535}[positions_type]
        assert np.array_equal(rig.vertices, np.round(QUAD_VERTICES * scale) / scale)  # c / (2^b - 1)
    assert rig.faces.tolist() == [[0, 1, 2], [0, 2, 3]]


@pytest.mark.parametrize("joint_type", [5121, 5123])
@pytest.mark.parametrize("weight_type", [5126, 5121, 5123])
def test_component_types_of_joints_and_weights(tmp_path, joint_type, weight_type):
    rig = load_quietly(Gltf.quad(joint_type=joint_type, weight_type=weight_type).write(tmp_path / "q.glb"))
    assert rig.joints[1].tolist() == [0, 1, 0, 0]
    if weight_type == 5126:
        assert rig.weights[1].tolist() == [0.75, 0.25, 0, 0]
    else:
        m = {5121: 255, 5123: 65535}[weight_type]
        expected = np.array([np.round(0.75 * m), np.round(0.25 * m)]) / m
        np.testing.assert_allclose(rig.weights[1, :2], expected / expected.sum(), rtol=1e-6)


def test_signed_normalized_minimum_clamps_to_minus_one(tmp_path):
    g = Gltf.quad()
    pos = np.array([[-128, -127, 0], [127, 0, 0], [127, 127, 0], [0, 127, 0]])
    g.primitive["attributes"]["POSITION"] = g.accessor(pos, 5120, "VEC3", normalized=True)
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert rig.vertices[0].tolist() == [-1.0, -1.0, 0.0]  # max(c / 127, -1)


def test_interleaved_attributes_with_stride_and_offsets(tmp_path):
    g = Gltf.quad()
    # POSITION and NORMAL interleaved (24-byte stride), behind 8 bytes of something else
    positions = QUAD_VERTICES.astype("<f4")
    normals = np.tile(np.array([0, 0, 1], dtype="<f4"), (4, 1))
    interleaved = np.concatenate([positions, normals], axis=1).tobytes()
    view = g.view(b"\xff" * 8 + interleaved, stride=24)
    g.primitive["attributes"]["POSITION"] = g.accessor(positions, 5126, "VEC3", view=view, byte_offset=8)
    g.primitive["attributes"]["NORMAL"] = g.accessor(normals, 5126, "VEC3", view=view, byte_offset=20)
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert np.array_equal(rig.vertices, QUAD_VERTICES)
    assert np.array_equal(rig.attributes["NORMAL"], np.tile([0.0, 0, 1], (4, 1)))


def test_sparse_accessor_over_a_buffer_view_and_over_zeros(tmp_path):
    g = Gltf.quad()
    # POSITION: all zeros (no bufferView) + sparse substitution of every vertex
    idx_view = g.view(np.array([0, 1, 2, 3], dtype="<u2").tobytes())
    val_view = g.view(QUAD_VERTICES.astype("<f4").tobytes())
    sparse = {"count": 4, "indices": {"bufferView": idx_view, "componentType": 5123},
              "values": {"bufferView": val_view}}
    g.primitive["attributes"]["POSITION"] = g.accessor(QUAD_VERTICES, 5126, "VEC3", view=False, sparse=sparse)
    # TEXCOORD_0: a bufferView base with vertex 2 replaced
    base = np.array([[0, 0], [1, 0], [9, 9], [0, 1]], dtype="<f4")
    sparse = {"count": 1, "indices": {"bufferView": g.view(bytes([2])), "componentType": 5121},
              "values": {"bufferView": g.view(np.array([1, 1], dtype="<f4").tobytes())}}
    g.primitive["attributes"]["TEXCOORD_0"] = g.accessor(base, 5126, "VEC2", sparse=sparse)
    rig = load_gltf(g.write(tmp_path / "q.gltf"))
    assert np.array_equal(rig.vertices, QUAD_VERTICES)
    assert rig.attributes["TEXCOORD_0"].tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]


def test_accessor_without_buffer_view_is_zeros(tmp_path):
    g = Gltf.quad()
    g.primitive["attributes"]["TEXCOORD_0"] = g.accessor(np.zeros((4, 2)), 5126, "VEC2", view=False)
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert np.array_equal(rig.attributes["TEXCOORD_0"], np.zeros((4, 2)))


def test_padded_matrix_columns(tmp_path):
    """MAT3 of shorts and MAT2 of bytes start every column on a 4-byte boundary (spec 3.6.2.4)."""
    from cgaskin.rigs.gltf import _read_document
    g = Gltf.quad()
    m3 = np.arange(9).reshape(3, 3)  # row-major
    cols = b"".join(np.array(m3[:, c], dtype="<i2").tobytes() + b"\0\0" for c in range(3))
    a3 = g.accessor(None, 5122, "MAT3", view=g.view(cols * 2), count=2)
    m2 = np.array([[1, 2], [3, 4]])
    cols = b"".join(np.array(m2[:, c], dtype="<u1").tobytes() + b"\0\0" for c in range(2))
    a2 = g.accessor(None, 5121, "MAT2", view=g.view(cols), count=1)
    f = _read_document(g.write(tmp_path / "q.glb"))
    assert np.array_equal(f.accessor(a3, "test"), [m3, m3])
    assert np.array_equal(f.accessor(a2, "test"), [m2])


def test_triangle_strips_and_fans_and_skipped_points(tmp_path):
    g = Gltf.quad()
    prim = g.primitive
    strip = dict(prim, mode=5, indices=g.accessor([0, 1, 3, 2], 5121, "SCALAR"))
    fan = dict(prim, mode=6, indices=g.accessor([0, 1, 2, 3], 5121, "SCALAR"))
    points = dict(prim, mode=0)
    g.doc["meshes"][0]["primitives"] = [strip, fan, points]
    with pytest.warns(UserWarning, match=r"skipped 1 primitives that are not triangles \(POINTS\)"):
        rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert rig.n_vertices == 8  # two merged copies of the quad
    # strip triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}): (0,1,3), (1,2,3), both counter-clockwise;
    # fan (v_{i+1}, v_{i+2}, v_0): (1,2,0), (2,3,0); the second copy is offset by 4
    assert rig.faces.tolist() == [[0, 1, 3], [1, 2, 3], [5, 6, 4], [6, 7, 4]]


def test_several_primitives_and_nodes_merge_and_drop_partial_attributes(tmp_path):
    g = Gltf.quad()
    with_normals = dict(g.primitive)
    with_normals["attributes"] = dict(with_normals["attributes"],
                                      NORMAL=g.accessor(np.tile([0, 0, 1.0], (4, 1)), 5126, "VEC3"))
    g.doc["meshes"].append({"primitives": [with_normals]})
    g.doc["nodes"].append({"name": "quad2", "mesh": 1, "skin": 0})
    g.doc["scenes"][0]["nodes"].append(4)
    with pytest.warns(UserWarning, match=r"dropped attribute NORMAL: only 1 of 2 merged primitives have it"):
        rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert rig.n_vertices == 8 and rig.faces.max() == 7 and "NORMAL" not in rig.attributes


def test_several_skins_merge_into_one_skeleton(tmp_path):
    g = Gltf.quad()
    ibm = np.stack([np.eye(4)] * 2)
    ibm_b = np.eye(4)
    ibm_b[:3, 3] = [-0.5, 0, 0]
    ibm[1] = ibm_b
    g.doc["skins"][0]["inverseBindMatrices"] = g.accessor(ibm.transpose(0, 2, 1).reshape(2, 16), 5126, "MAT4")
    # skin 1: joint B with the same matrix (shared bone), joint A with another one (a new bone),
    # and a joint C under a non-joint node D
    other = np.stack([ibm_b, np.eye(4) * 2, np.eye(4)])
    other[1, 3, 3] = 1
    g.doc["nodes"] += [{"name": "D", "children": [5]}, {"name": "C"}, {"name": "quad2", "mesh": 0, "skin": 1}]
    g.doc["nodes"][2]["children"] = [4]
    g.doc["scenes"][0]["nodes"].append(6)
    g.doc["skins"].append({"joints": [2, 1, 5],
                           "inverseBindMatrices": g.accessor(other.transpose(0, 2, 1).reshape(3, 16), 5126, "MAT4")})
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    sk = rig.skeleton
    assert sk.names == ["Armature", "A", "B", "D", "C"]
    assert sk.parents.tolist() == [-1, 0, 1, 2, 3]
    # bones: skin 0 -> A, B; skin 1 -> B (shared), A with another matrix (new), C (new)
    assert sk.bone_nodes.tolist() == [1, 2, 1, 4]
    assert np.array_equal(sk.inverse_bind[2], other[1])
    # second copy of the quad: skin-1 joint slots 0 and 1 are bones 1 (B, shared) and 2 (A, new)
    assert rig.joints[5:7].tolist() == [[1, 2, 0, 0], [1, 2, 0, 0]]


def test_matrix_node_is_column_major_and_decomposed(tmp_path):
    g = Gltf.quad()
    angle = 0.3
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3] = rot @ np.diag([-2.0, 3.0, 0.5])  # a reflection: det < 0
    m[:3, 3] = [1, 2, 3]
    g.doc["nodes"][1]["matrix"] = m.T.reshape(-1).tolist()
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    sk = rig.skeleton
    assert np.array_equal(sk.rest_matrices[1], m)
    np.testing.assert_allclose(sk.rest_translations[1], [1, 2, 3])
    np.testing.assert_allclose(sk.rest_scales[1], [-2, 3, 0.5], atol=1e-12)
    np.testing.assert_allclose(trs_to_matrix(sk.rest_translations[1], sk.rest_rotations[1], sk.rest_scales[1]), m, atol=1e-12)


def test_sheared_matrix_keeps_the_exact_matrix():
    m = np.eye(4)
    m[0, 1] = 0.5  # shear
    t, q, s = matrix_to_trs(m)
    assert np.isfinite(q).all() and np.isclose(np.linalg.norm(q), 1)
    assert not np.allclose(trs_to_matrix(t, q, s), m)  # TRS cannot hold it; rest_matrices must


def test_near_180_degree_rotation_matrix_to_trs():
    """assimp's FBX PreRotation nodes are 179.999995 degree rotations."""
    angle = np.radians(179.999995)
    axis = np.array([1.0, 2.0, 2.0]) / 3
    q = np.append(axis * np.sin(angle / 2), np.cos(angle / 2))
    m = trs_to_matrix([0, 0, 0], q, [1, 1, 1])
    _, q2, s2 = matrix_to_trs(m)
    np.testing.assert_allclose(q2, q, atol=1e-15)
    np.testing.assert_allclose(s2, 1, atol=1e-15)


def test_animations(tmp_path):
    g = Gltf.quad()
    times = g.accessor([0.0, 0.5, 1.0], 5126, "SCALAR", min=[0], max=[1])
    translations = g.accessor([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 5126, "VEC3")
    # rotations as normalized shorts (allowed for rotation outputs): (0, 0, 0, 1) = (0, 0, 0, 32767)
    rotations = g.accessor([[0, 0, 0, 32767]] * 9, 5122, "VEC4", normalized=True)
    scales = g.accessor([[1, 1, 1], [2, 2, 2], [3, 3, 3]], 5126, "VEC3")
    samplers = [{"input": times, "output": translations},  # LINEAR by default
                {"input": times, "output": rotations, "interpolation": "CUBICSPLINE"},
                {"input": times, "output": scales, "interpolation": "STEP"},
                {"input": times, "output": g.accessor([0.0, 1, 2], 5126, "SCALAR")}]
    channels = [{"sampler": 0, "target": {"node": 2, "path": "translation"}},
                {"sampler": 1, "target": {"node": 1, "path": "rotation"}},
                {"sampler": 2, "target": {"node": 0, "path": "scale"}},
                {"sampler": 3, "target": {"node": 3, "path": "weights"}},      # morph weights
                {"sampler": 0, "target": {"node": 3, "path": "translation"}}]  # the mesh node
    g.doc["animations"] = [{"name": "move", "samplers": samplers, "channels": channels},
                           {"samplers": samplers[:1], "channels": channels[:1]}]
    with pytest.warns(UserWarning, match=r"skipped 1 animation channels of morph-target weights and 1 of nodes outside"):
        rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert [c.name for c in rig.clips] == ["move", "clip1"]
    t, r, s = rig.clips[0].channels
    assert (t.node, t.path, t.interpolation) == (2, "translation", "LINEAR")
    assert t.values.tolist() == [[0, 0, 0], [1, 0, 0], [2, 0, 0]] and t.times.tolist() == [0, 0.5, 1]
    assert (r.node, r.interpolation) == (1, "CUBICSPLINE") and r.values.shape == (3, 3, 4)
    assert np.array_equal(r.values, np.tile([0, 0, 0, 1.0], (3, 3, 1)))
    assert (s.node, s.interpolation) == (0, "STEP") and s.values.shape == (3, 3)
    assert rig.clips[0].duration == 1.0
