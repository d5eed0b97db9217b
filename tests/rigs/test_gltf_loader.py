"""glTF loader: the real models, synthetic files for each spec feature, and broken files."""
import base64
import copy
import json
import struct
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cgaskin import rigs
from cgaskin.errors import CgaskinError, ModelFormatError, NoSkinError
from cgaskin.rigs.gltf import load_gltf, matrix_to_trs, trs_to_matrix

# --- the real models (counts from models/README.md) ---------------------------------------------

MODELS = {
    # file: (vertices, faces, bones, clip names)
    "Arm5.glb": (2935, 5037, 23, []),
    "3Cylinder4bones.glb": (509, 758, 4, []),
    "PlaneWith3Bones.glb": (25, 32, 3, []),
    "Fox.glb": (1728, 576, 24, ["Survey", "Walk", "Run"]),
    "simple_skin.gltf": (10, 8, 2, ["clip0"]),
    "quad_skin.glb": (4, 2, 10, []),
}


def load_quietly(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_gltf(path)


def assert_valid_rig(rig):
    """The Rig invariants every loader result must satisfy (no NaN, consistent indices)."""
    sk = rig.skeleton
    n, j, b = rig.n_vertices, sk.n_nodes, sk.n_bones
    assert rig.vertices.shape == (n, 3) and rig.vertices.dtype == np.float64
    assert rig.faces.ndim == 2 and rig.faces.shape[1] == 3 and rig.faces.dtype == np.int64
    assert rig.joints.shape == (n, 4) and rig.joints.dtype == np.int64
    assert rig.weights.shape == (n, 4) and rig.weights.dtype == np.float64
    assert ((rig.faces >= 0) & (rig.faces < n)).all()
    assert ((rig.joints >= 0) & (rig.joints < b)).all()
    assert (rig.weights >= 0).all() and ((rig.weights > 0).sum(axis=1) >= 1).all()
    np.testing.assert_allclose(rig.weights.sum(axis=1), 1.0, rtol=0, atol=2e-15)
    assert len(sk.names) == j == len(set(sk.names))
    assert (sk.parents < np.arange(j)).all() and (sk.parents >= -1).all()
    np.testing.assert_allclose(np.linalg.norm(sk.rest_rotations, axis=1), 1.0, atol=1e-12)
    assert sk.rest_matrices.shape == (j, 4, 4) and sk.inverse_bind.shape == (b, 4, 4)
    assert ((sk.bone_nodes >= 0) & (sk.bone_nodes < j)).all()
    arrays = [rig.vertices, rig.weights, sk.rest_translations, sk.rest_rotations, sk.rest_scales,
              sk.rest_matrices, sk.inverse_bind, *rig.attributes.values()]
    for clip in rig.clips:
        for ch in clip.channels:
            assert 0 <= ch.node < j
            assert (np.diff(ch.times) > 0).all()
            arrays += [ch.times, ch.values]
    for a in arrays:
        assert np.isfinite(a).all()


@pytest.mark.parametrize("name", sorted(MODELS))
def test_real_model_counts(models_dir, name):
    n_vertices, n_faces, n_bones, clips = MODELS[name]
    rig = load_quietly(models_dir / name)
    assert (rig.n_vertices, rig.n_faces, rig.skeleton.n_bones) == (n_vertices, n_faces, n_bones)
    assert [c.name for c in rig.clips] == clips
    assert rig.name == name.rsplit(".", 1)[0]
    assert_valid_rig(rig)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_facade_load_picks_the_gltf_reader(models_dir, name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rig = rigs.load(models_dir / name)
    assert rig.n_vertices == MODELS[name][0]


def test_fox_clips(models_dir):
    rig = load_quietly(models_dir / "Fox.glb")
    assert "TEXCOORD_0" in rig.attributes and "NORMAL" not in rig.attributes  # Fox has no normals
    assert rig.faces.tolist()[:2] == [[0, 1, 2], [3, 4, 5]]  # non-indexed: 0..n-1
    for clip in rig.clips:
        assert len(clip.channels) == 21
        assert {ch.path for ch in clip.channels} == {"translation", "rotation"}
        assert {ch.interpolation for ch in clip.channels} == {"LINEAR"}
    assert [round(c.duration, 4) for c in rig.clips] == [3.4167, 0.7083, 1.1583]


def test_simple_skin_structure(models_dir):
    rig = load_quietly(models_dir / "simple_skin.gltf")
    sk = rig.skeleton
    # the mesh node is the parent of the root joint: it is a non-joint ancestor in the skeleton
    assert sk.names == ["node0", "node1", "node2"]
    assert sk.parents.tolist() == [-1, 0, 1]
    assert sk.bone_nodes.tolist() == [1, 2]
    (ch,) = rig.clips[0].channels
    assert (ch.node, ch.path, ch.interpolation) == (2, "rotation", "LINEAR")
    assert ch.times.shape == (12,) and ch.values.shape == (12, 4)
    assert rig.clips[0].duration == 5.5


def test_quad_skin_keeps_the_four_largest_of_ten_influences(models_dir):
    with pytest.warns(UserWarning, match=r"quad_skin.glb: 3 vertices have more than 4 bone influences \(up to 10\)"):
        rig = load_gltf(models_dir / "quad_skin.glb")
    # vertex 0: 10 influences, the 4 largest are bones 5, 0, 1, 3 (0.216, 0.207, 0.113, 0.090)
    assert rig.joints[0].tolist() == [5, 0, 1, 3]
    np.testing.assert_allclose(rig.weights[0], np.array([0.2157, 0.2069, 0.1126, 0.0901]) / 0.6253, atol=2e-4)


@pytest.mark.parametrize("name, deviation", [("Arm5.glb", "0.00181"), ("3Cylinder4bones.glb", "0.000899")])
def test_assimp_weights_are_renormalised_with_a_warning(models_dir, name, deviation):
    with pytest.warns(UserWarning, match=rf"weights that do not sum to 1 \(max deviation {deviation}"):
        load_gltf(models_dir / name)


def test_matrix_nodes_keep_the_exact_matrix(models_dir):
    """3Cylinder4bones stores its nodes as column-major matrices (assimp's FBX PreRotation nodes)."""
    import pygltflib
    doc = pygltflib.GLTF2().load(str(models_dir / "3Cylinder4bones.glb"))
    rig = load_quietly(models_dir / "3Cylinder4bones.glb")
    sk = rig.skeleton
    by_name = {node.name: node for node in doc.nodes}
    matrix_nodes = [i for i, name in enumerate(sk.names) if by_name[name].matrix is not None]
    assert matrix_nodes
    for i in matrix_nodes:
        expected = np.array(by_name[sk.names[i]].matrix).reshape(4, 4).T
        assert np.array_equal(sk.rest_matrices[i], expected)
        rebuilt = trs_to_matrix(sk.rest_translations[i], sk.rest_rotations[i], sk.rest_scales[i])
        np.testing.assert_allclose(rebuilt, expected, rtol=0, atol=1e-12)


# --- synthetic files: one spec feature at a time -----------------------------------------------------

class Gltf:
    """Builds small glTF documents: a skinned quad on a 2-joint chain under a non-joint root."""

    def __init__(self):
        self.blob = bytearray()
        self.doc = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [], "accessors": []}

    def view(self, data: bytes, stride=None) -> int:
        self.blob += b"\0" * (-len(self.blob) % 4)
        view = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if stride:
            view["byteStride"] = stride
        self.blob += data
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, array, component_type, type_, *, normalized=False, view=None, byte_offset=0,
                 count=None, **extra) -> int:
        dtype = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}[component_type]
        array = np.asarray(array)
        if view is None:
            view = self.view(array.astype(dtype).tobytes())
        acc = {"bufferView": view, "byteOffset": byte_offset, "componentType": component_type,
               "count": len(array) if count is None else count, "type": type_, **extra}
        if normalized:
            acc["normalized"] = True
        if view is False:
            del acc["bufferView"], acc["byteOffset"]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    @classmethod
    def quad(cls, positions_type=5126, index_type=5123, joint_type=5121, weight_type=5126):
        g = cls()
        positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float) * 0.5
        if positions_type == 5126:
            pos = g.accessor(positions, 5126, "VEC3", min=[0, 0, 0], max=[0.5, 0.5, 0])
        else:  # KHR_mesh_quantization style: normalized integers
            scale = {5120: 127, 5121: 255, 5122: 32767, 5123: 65535}[positions_type]
            pos = g.accessor(np.round(positions * scale), positions_type, "VEC3", normalized=True)
        weights = np.array([[1, 0, 0, 0], [0.75, 0.25, 0, 0], [0.5, 0.5, 0, 0], [0, 1, 0, 0]])
        if weight_type != 5126:
            weights = np.round(weights * {5121: 255, 5123: 65535}[weight_type])
        g.doc.update(
            scene=0, scenes=[{"nodes": [0, 3]}],
            nodes=[{"name": "Armature", "translation": [0, 0, 1], "children": [1]},
                   {"name": "A", "children": [2]},
                   {"name": "B", "translation": [0.5, 0, 0]},
                   {"name": "quad", "mesh": 0, "skin": 0}],
            meshes=[{"primitives": [{"attributes": {
                "POSITION": pos,
                "JOINTS_0": g.accessor([[0, 1, 0, 0]] * 4, joint_type, "VEC4"),
                "WEIGHTS_0": g.accessor(weights, weight_type, "VEC4", normalized=weight_type != 5126)},
                "indices": g.accessor([0, 1, 2, 0, 2, 3], index_type, "SCALAR")}]}],
            skins=[{"joints": [1, 2]}])
        return g

    @property
    def primitive(self):
        return self.doc["meshes"][0]["primitives"][0]

    def write(self, path, kind=None):
        """Write as .glb, .gltf with a data: URI, or .gltf with an external .bin (by extension/kind)."""
        doc = copy.deepcopy(self.doc)
        blob = bytes(self.blob) + b"\0" * (-len(self.blob) % 4)
        doc["buffers"] = [{"byteLength": len(blob)}]
        if path.suffix == ".glb":
            text = json.dumps(doc).encode()
            text += b" " * (-len(text) % 4)
            body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
            path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)
        else:
            if kind == "external":
                (path.parent / "my data.bin").write_bytes(blob)
                doc["buffers"][0]["uri"] = "my%20data.bin"  # URIs are percent-encoded
            else:
                doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
            path.write_text(json.dumps(doc))
        return path


QUAD_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]) * 0.5


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


# --- broken files -------------------------------------------------------------------------------------

MALFORMED = [
    ("BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
     r"POSITION \(accessor 2\) holds non-finite coordinates: vertex 0 is \[-inf"),
    ("IncorrectVertexArrays/Cube.gltf", r"TRIANGLES needs a multiple of 3 indices/vertices, got 35"),
    ("IndexOutOfRange/IndexOutOfRange.gltf", r"index 255 at position 0 of accessor 0 is out of range: "
                                             r"the primitive has 24 vertices"),
    ("MissingBin/BoxTextured.gltf", r"buffer 0 refers to the file 'BoxTextured0.bin', which is missing"),
    ("TestNoRootNode/NoScene.gltf", r"holds no node at all"),
]


@pytest.mark.parametrize("name, message", MALFORMED)
def test_malformed_files_get_a_specific_error(models_dir, name, message):
    path = models_dir / "malformed" / name
    with pytest.raises(ModelFormatError, match=message) as info:
        load_gltf(path)
    assert str(info.value).startswith(path.name + ": ")


def test_valid_file_without_skin_raises_no_skin_error(tmp_path):
    g = Gltf.quad()
    del g.doc["nodes"][3]["skin"]
    with pytest.raises(NoSkinError, match=r"q.glb: holds no skinned mesh \(1 mesh node\(s\) without a skin\); "
                                          r"cgaskin needs a skin \(JOINTS_0/WEIGHTS_0 \+ node.skin\)"):
        load_gltf(g.write(tmp_path / "q.glb"))


def mutate(g, change):
    change(g)
    return g


@pytest.mark.parametrize("change, message", [
    (lambda g: g.doc["accessors"][0].update(byteOffset=40), r"accessor 0 reads bytes \[40, 88\) past the end of its bufferView 0 \(bytes \[0, 48\)\)"),
    (lambda g: g.doc["accessors"][0].update(count=400), r"attribute JOINTS_0 has 4 elements but POSITION has 400"),
    (lambda g: g.doc["accessors"][0].update(componentType=5124), r"accessor 0 \(mesh 0 primitive 0 POSITION\) has unknown componentType 5124"),
    (lambda g: g.doc["accessors"][0].update(type="VEC7"), r"unknown type 'VEC7'"),
    (lambda g: g.doc["bufferViews"][0].update(byteStride=8), r"accessor 0: byteStride 8 is smaller than its 12-byte elements"),
    (lambda g: g.doc["bufferViews"][0].update(byteLength=10**6), r"bufferView 0 spans bytes \[0, 1000000\) but buffer 0 has only"),
    (lambda g: g.primitive.update(indices=99), r"mesh 0 primitive 0 indices accessor = 99 is out of range: the file has \d+ accessors"),
    (lambda g: g.primitive["attributes"].pop("WEIGHTS_0"), r"has only one of JOINTS_0 / WEIGHTS_0"),
    (lambda g: g.primitive["attributes"].update(TEXCOORD_0=3), r"attribute TEXCOORD_0 has 6 elements but POSITION has 4"),
    (lambda g: g.doc["nodes"][2].update(children=[0]), r"the node hierarchy has a cycle through node 0"),
    (lambda g: g.doc["nodes"].__setitem__(0, {"name": "Armature", "children": [1, 0]}), r"node 0 is a child of both node 0"),
    (lambda g: g.doc["skins"][0].update(joints=[1, 7]), r"skin 0 joint = 7 is out of range: the file has 4 nodes"),
    (lambda g: g.doc["skins"][0].update(joints=[1]), r"vertex 1 is weighted to joint 1 but skin 0 has 1 joints"),
    (lambda g: g.doc.update(scene=3), r"the default 'scene' = 3 is out of range"),
    (lambda g: g.doc["asset"].update(version="1.0"), r"glTF version 1.0 is not supported"),
    (lambda g: g.doc.update(extensionsRequired=["KHR_draco_mesh_compression"]), r"requires KHR_draco_mesh_compression"),
    (lambda g: g.doc["nodes"][1].update(rotation=[0, 0, 0, 0]), r"node 1 rotation is the zero quaternion"),
    (lambda g: g.doc["nodes"][1].update(matrix=[1, 2, 3]), r"node 1 matrix must be a list of 16 numbers"),
    (lambda g: g.doc.update(nodes=5), r"not a valid glTF document: a property has the wrong JSON type"),
])
def test_inconsistent_documents_are_refused(tmp_path, change, message):
    with pytest.raises(ModelFormatError, match=message):
        load_gltf(mutate(Gltf.quad(), change).write(tmp_path / "q.glb"))


def test_nan_weights_are_a_format_error(tmp_path):
    g = Gltf.quad()
    g.primitive["attributes"]["WEIGHTS_0"] = g.accessor([[np.nan, 0, 0, 0]] + [[1, 0, 0, 0]] * 3, 5126, "VEC4")
    with pytest.raises(ModelFormatError, match=r"q.glb: vertex 0 has non-finite weights"):
        load_gltf(g.write(tmp_path / "q.glb"))


def test_missing_file_directory_and_bad_json(tmp_path):
    with pytest.raises(ModelFormatError, match=r"nothere.glb: no such file"):
        load_gltf(tmp_path / "nothere.glb")
    with pytest.raises(ModelFormatError, match=r"is a directory"):
        load_gltf(tmp_path)
    (tmp_path / "bad.gltf").write_text('{"asset": {"version": "2.0"}, "nodes": [')
    with pytest.raises(ModelFormatError, match=r"bad.gltf: the glTF JSON is malformed: Expecting value: line 1"):
        load_gltf(tmp_path / "bad.gltf")
    (tmp_path / "empty.gltf").write_bytes(b"")
    with pytest.raises(ModelFormatError, match=r"empty.gltf: the file is empty"):
        load_gltf(tmp_path / "empty.gltf")


def test_unknown_extension_lists_the_supported_ones(tmp_path):
    with pytest.raises(ModelFormatError, match=r"unknown model format '.xyz'; cgaskin reads .glb, .gltf, .fbx, .dae"):
        rigs.load(tmp_path / "model.xyz")


def test_buffer_shorter_than_declared(tmp_path):
    g = Gltf.quad()
    path = g.write(tmp_path / "q.gltf")
    doc = json.loads(path.read_text())
    doc["buffers"][0]["byteLength"] += 4
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFormatError, match=r"buffer 0 \(its data: URI\) holds \d+ bytes but declares byteLength"):
        load_gltf(path)


# --- corrupted copies of the real models --------------------------------------------------------

def glb_chunks(data: bytes):
    json_length = struct.unpack_from("<I", data, 12)[0]
    return 20, 20 + json_length  # JSON chunk payload [start, end)


@pytest.mark.parametrize("name", ["PlaneWith3Bones.glb", "Fox.glb"])
def test_truncated_glb(models_dir, tmp_path, name):
    data = (models_dir / name).read_bytes()
    start, end = glb_chunks(data)
    for length in [0, 3, 11, 12, 16, 19, 20, (start + end) // 2, end, end + 7, len(data) - 100, len(data) - 1]:
        path = tmp_path / f"cut{length}.glb"
        path.write_bytes(data[:length])
        with pytest.raises(ModelFormatError, match=r"truncated GLB|the file is empty|JSON") as info:
            load_gltf(path)
        assert path.name in str(info.value)


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(flips=st.lists(st.tuples(st.floats(0, 1, exclude_max=True), st.integers(1, 255)), min_size=1, max_size=4))
@pytest.mark.parametrize("name", ["PlaneWith3Bones.glb", "simple_skin.gltf"])
def test_flipped_json_bytes_give_an_error_or_a_valid_rig(models_dir, fuzz_dir, name, flips):
    data = bytearray((models_dir / name).read_bytes())
    start, end = glb_chunks(data) if name.endswith(".glb") else (0, len(data))
    for where, xor in flips:
        data[start + int(where * (end - start))] ^= xor
    path = fuzz_dir / name
    path.write_bytes(bytes(data))
    try:
        rig = load_quietly(path)
    except CgaskinError as exc:
        assert isinstance(exc, ModelFormatError) and str(exc).startswith(name + ": ")
        return
    assert_valid_rig(rig)


def edit_simple_skin(models_dir, tmp_path, edit):
    """Copy simple_skin.gltf with ``edit(buffer0: bytearray)`` applied to its first data: buffer."""
    doc = json.loads((models_dir / "simple_skin.gltf").read_text())
    uri = doc["buffers"][0]["uri"]
    header, payload = uri.split(",", 1)
    buffer = bytearray(base64.b64decode(payload))
    edit(buffer)
    doc["buffers"][0]["uri"] = header + "," + base64.b64encode(bytes(buffer)).decode()
    path = tmp_path / "simple_skin.gltf"
    path.write_text(json.dumps(doc))
    return path


def test_nan_injected_into_positions(models_dir, tmp_path):
    # buffer 0 = 24 ushort indices (48 bytes), then 10 float32 VEC3 positions
    path = edit_simple_skin(models_dir, tmp_path, lambda b: b.__setitem__(slice(48 + 12 * 3 + 4, 48 + 12 * 3 + 8),
                                                                         struct.pack("<f", np.nan)))
    with pytest.raises(ModelFormatError, match=r"simple_skin.gltf: mesh 0 primitive 0 POSITION \(accessor 1\) holds "
                                               r"non-finite coordinates: vertex 3 is \[\S+, nan, \S+\]"):
        load_gltf(path)


def test_out_of_range_index_injected(models_dir, tmp_path):
    path = edit_simple_skin(models_dir, tmp_path, lambda b: b.__setitem__(slice(10, 12), struct.pack("<H", 10)))
    with pytest.raises(ModelFormatError, match=r"index 10 at position 5 of accessor 0 is out of range: "
                                               r"the primitive has 10 vertices"):
        load_gltf(path)
