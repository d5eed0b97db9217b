"""glTF loader on broken files: the malformed samples, inconsistent documents, missing files, and
corrupted copies of the real models, each with a specific error.
"""
import base64
import json
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cgaskin import rigs
from cgaskin.errors import CgaskinError, ModelFormatError, NoSkinError
from cgaskin.rigs.gltf import load_gltf

from tests.helpers.gltf_files import Gltf, assert_valid_rig, load_quietly


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


def test_valid_file_without_a_mesh_raises_no_skin_error(tmp_path):
    """(A mesh without a skin loads as a rigid bone: tests/rigs/test_skinless.py.)"""
    g = Gltf.quad()
    del g.doc["nodes"][3]["skin"], g.doc["nodes"][3]["mesh"]
    with pytest.raises(NoSkinError, match=r"q.glb: holds no mesh \(no node of its scene has one\): nothing to load"):
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


def test_unknown_extension_goes_to_assimp(tmp_path):
    """No fixed list of extensions: assimp decides, and its "cannot read" says how cgaskin reads models
    (or, without the assimp tool, how to install it)."""
    with pytest.raises(ModelFormatError, match=r"model.xyz: no such file"):
        rigs.load(tmp_path / "model.xyz")
    (tmp_path / "model.xyz").write_text("hello\n")
    with pytest.raises(ModelFormatError, match=r"model.xyz: assimp cannot read this file .*cgaskin reads glTF, "
                                               r".glb and .gltf, natively and every other format through "
                                               r"assimp|apt-get install assimp-utils"):
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
