"""glTF files for the loader tests: small documents built in memory (``Gltf``: a skinned quad on a
2-joint chain, one spec feature changed at a time), and the invariants every loaded rig satisfies."""
import base64
import copy
import json
import struct
import warnings

import numpy as np

from cgaskin.rigs.gltf import load_gltf


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
