"""glTF export: save -> load round trips, and output that other glTF readers accept."""
import json
import warnings

import numpy as np
import pygltflib
import pytest

from cgaskin import rigs
from cgaskin import Channel, Clip, Rig, Skeleton, check_mesh
from cgaskin.errors import InvalidInputError, ModelFormatError
from cgaskin.rigs.export import save_gltf
from cgaskin.rigs.gltf import load_gltf, trs_to_matrix

MODELS = ["Arm5.glb", "3Cylinder4bones.glb", "PlaneWith3Bones.glb", "Fox.glb", "simple_skin.gltf",
          "quad_skin.glb"]
SKELETON_ARRAYS = ["parents", "rest_translations", "rest_rotations", "rest_scales", "rest_matrices",
                   "bone_nodes", "inverse_bind"]


def load_quietly(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_gltf(path)


def f32(a):
    """float64 array holding the float32 rounding of ``a``: what glTF storage keeps."""
    return np.asarray(a, dtype=np.float64).astype(np.float32).astype(np.float64)


def random_quaternions(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def float64_rig(n_bones=3, rings=13, per_ring=8, seed=1) -> Rig:
    """A tube along x bound to a chain of bones, with float64 data everywhere and three clips."""
    rng = np.random.default_rng(seed)
    x = np.linspace(0, n_bones, rings)
    angle = np.linspace(0, 2 * np.pi, per_ring, endpoint=False)
    vertices = np.stack([np.repeat(x, per_ring), np.tile(np.cos(angle), rings), np.tile(np.sin(angle), rings)], 1)
    vertices += rng.normal(scale=1e-3, size=vertices.shape)  # not float32-representable
    faces = []
    for r in range(rings - 1):
        for k in range(per_ring):
            a, b = r * per_ring + k, r * per_ring + (k + 1) % per_ring
            faces += [[a, b, b + per_ring], [a, b + per_ring, a + per_ring]]
    # each vertex: the two nearest bones, linear falloff
    lower = np.clip(np.floor(vertices[:, 0]).astype(int), 0, n_bones - 1)
    upper = np.minimum(lower + 1, n_bones - 1)
    t = np.clip(vertices[:, 0] - lower, 0, 1)
    joints = np.stack([lower, upper, np.zeros_like(lower), np.zeros_like(lower)], 1)
    weights = np.stack([1 - t, t, np.zeros_like(t), np.zeros_like(t)], 1)
    weights[lower == upper] = [1, 0, 0, 0]  # past the last bone
    weights[:, :2] += rng.uniform(0, 1e-3, size=(len(t), 2)) * (weights[:, :2] > 0)
    weights /= weights.sum(axis=1, keepdims=True)

    # nodes: a non-joint root, then the bone chain
    j = n_bones + 1
    parents = np.arange(-1, j - 1)
    translations = np.vstack([[0.1, -0.2, 0.3], np.tile([1.0, 0, 0], (j - 1, 1))])
    translations[1] = [0.0, 0, 0]
    rotations = random_quaternions(rng, j)
    scales = np.ones((j, 3))
    scales[0] = [1.5, 0.7, 2.0]  # non-uniform: only TRS and matrices can hold it
    matrices = np.array([trs_to_matrix(*trs) for trs in zip(translations, rotations, scales)])
    globals_ = np.zeros_like(matrices)
    for i in range(j):
        globals_[i] = matrices[i] if parents[i] < 0 else globals_[parents[i]] @ matrices[i]
    bone_nodes = np.arange(1, j)
    skeleton = Skeleton(names=["root"] + [f"bone{k}" for k in range(n_bones)], parents=parents,
                        rest_translations=translations, rest_rotations=rotations, rest_scales=scales,
                        rest_matrices=matrices, bone_nodes=bone_nodes,
                        inverse_bind=np.linalg.inv(globals_[bone_nodes]))
    times = np.cumsum(rng.uniform(0.05, 0.5, size=6))
    clips = [
        Clip("bend", (Channel(2, "rotation", "LINEAR", times, random_quaternions(rng, 6)),
                      Channel(1, "translation", "STEP", times[:4], rng.normal(size=(4, 3))))),
        Clip("pulse", (Channel(j - 1, "scale", "CUBICSPLINE", times, rng.uniform(0.5, 2, size=(6, 3, 3))),)),
    ]
    attributes = {"NORMAL": np.stack([np.zeros(len(vertices)), vertices[:, 1], vertices[:, 2]], 1),
                  "TEXCOORD_0": rng.random((len(vertices), 2))}
    # the canonical form every Rig holds (unused slots -> bone 0), as a constructor would make it
    vertices, faces, joints, weights = check_mesh(vertices, faces, joints, weights, n_bones=n_bones)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights,
               skeleton=skeleton, clips=clips, attributes=attributes, name="tube")


def assert_same_rig(a: Rig, b: Rig, convert=lambda x: x):
    """Bit-identical arrays, after ``convert`` for the attributes (the only float32-stored ones:
    positions, weights, inverse binds and keyframes carry their residuals)."""
    assert np.array_equal(b.vertices, a.vertices)  # always exact: float32 + residuals in the extras
    assert np.array_equal(b.faces, a.faces)
    assert np.array_equal(b.joints, a.joints)
    assert np.array_equal(b.weights, a.weights)  # always exact: float32 + residuals in the extras
    assert b.skeleton.names == a.skeleton.names
    for name in SKELETON_ARRAYS:
        assert np.array_equal(getattr(b.skeleton, name), getattr(a.skeleton, name)), name
    assert [c.name for c in b.clips] == [c.name for c in a.clips]
    for ca, cb in zip(a.clips, b.clips):
        assert len(ca.channels) == len(cb.channels)
        for x, y in zip(ca.channels, cb.channels):
            assert (x.node, x.path, x.interpolation) == (y.node, y.path, y.interpolation)
            assert np.array_equal(y.times, x.times)
            assert np.array_equal(y.values, x.values)
    assert sorted(a.attributes) == sorted(b.attributes)
    for name in a.attributes:
        assert np.array_equal(b.attributes[name], convert(a.attributes[name]))


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
@pytest.mark.parametrize("name", MODELS)
def test_round_trip_of_real_models_is_bit_identical(models_dir, tmp_path, name, suffix):
    rig = load_quietly(models_dir / name)
    path = rigs.save(rig, tmp_path / ("copy" + suffix))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the saved file is clean: no renormalisation, no skipping
        again = load_gltf(path)
    assert_same_rig(rig, again)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_float64_rig_round_trips_exactly_but_its_attributes(tmp_path, suffix):
    rig = float64_rig()
    assert not np.array_equal(rig.vertices, f32(rig.vertices))  # really float64 data
    path = save_gltf(rig, tmp_path / ("tube" + suffix))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = load_gltf(path)
    # attributes: float32 rounding of the originals; positions, weights, inverse binds and
    # keyframes (float32 + residuals), faces, joints, hierarchy and node TRS (JSON numbers): exact
    assert_same_rig(rig, again, convert=f32)
    # what other readers use: the float32 POSITION, the originals rounded
    doc = pygltflib.GLTF2().load(str(path))
    (prim,) = doc.meshes[0].primitives
    assert set(prim.extras["cgaskin"]) <= {"POSITION_LO", "POSITION_LO2", "WEIGHTS_0_LO", "WEIGHTS_0_LO2"}
    assert {"POSITION_LO", "POSITION_LO2"} <= set(prim.extras["cgaskin"])
    assert not [name for name in vars(prim.attributes) if name.startswith("_CGASKIN")]
    # and a second round trip changes nothing any more
    again2 = load_gltf(save_gltf(again, tmp_path / ("again" + suffix)))
    assert_same_rig(again, again2)


def test_output_is_valid_gltf(models_dir, tmp_path):
    rig = load_quietly(models_dir / "Fox.glb")
    path = save_gltf(rig, tmp_path / "fox.glb")
    doc = pygltflib.GLTF2().load(str(path))
    assert doc.asset.version == "2.0"
    (prim,) = doc.meshes[0].primitives
    position = doc.accessors[prim.attributes.POSITION]
    assert (position.componentType, position.type) == (5126, "VEC3")
    assert np.array_equal(position.min, rig.vertices.min(axis=0))
    assert np.array_equal(position.max, rig.vertices.max(axis=0))
    assert doc.accessors[prim.attributes.JOINTS_0].componentType == 5121  # 24 bones: unsigned byte
    assert doc.accessors[prim.attributes.WEIGHTS_0].componentType == 5126
    assert doc.accessors[prim.indices].componentType == 5125
    (skin,) = doc.skins
    assert skin.joints == rig.skeleton.bone_nodes.tolist()
    mesh_node = doc.nodes[-1]
    assert (mesh_node.mesh, mesh_node.skin, mesh_node.matrix, mesh_node.translation) == (0, 0, None, None)
    assert doc.scenes[doc.scene].nodes[-1] == len(doc.nodes) - 1
    for anim in doc.animations:
        for sampler in anim.samplers:
            times = doc.accessors[sampler.input]
            assert times.min is not None and times.max is not None  # required by the spec
    # buffer views are 4-byte aligned and inside the buffer
    for view in doc.bufferViews:
        assert view.byteOffset % 4 == 0 and view.byteOffset + view.byteLength <= doc.buffers[0].byteLength


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_trimesh_reads_the_output(models_dir, tmp_path, suffix):
    trimesh = pytest.importorskip("trimesh")
    rig = load_quietly(models_dir / "Arm5.glb")
    scene = trimesh.load(save_gltf(rig, tmp_path / ("arm" + suffix)))
    (mesh,) = scene.geometry.values()
    assert mesh.faces.shape == (5037, 3)
    np.testing.assert_allclose(mesh.bounds, [rig.vertices.min(0), rig.vertices.max(0)], rtol=1e-6)


def test_many_bones_use_unsigned_short_joints(tmp_path):
    rig = float64_rig(n_bones=300, rings=301, per_ring=3)
    path = save_gltf(rig, tmp_path / "long.glb")
    doc = pygltflib.GLTF2().load(str(path))
    assert doc.accessors[doc.meshes[0].primitives[0].attributes.JOINTS_0].componentType == 5123
    assert np.array_equal(load_gltf(path).joints, rig.joints)


def test_matrix_nodes_stay_matrices_unless_animated(tmp_path):
    rig = float64_rig()
    sk = rig.skeleton
    matrices = sk.rest_matrices.copy()
    matrices[0, 0, 1] += 0.25  # shear on the (non-animated) root
    matrices[2, 1, 0] += 1e-3  # and on bone1, animated by clip "bend": glTF wants TRS there
    rig = Rig(**{**rig.__dict__, "skeleton": Skeleton(**{**sk.__dict__, "rest_matrices": matrices})})
    with pytest.warns(UserWarning, match=r"node 'bone1' is animated, so glTF requires TRS"):
        path = save_gltf(rig, tmp_path / "shear.gltf")
    nodes = json.loads(path.read_text())["nodes"]
    assert "matrix" in nodes[0] and "translation" not in nodes[0]
    assert np.array_equal(np.array(nodes[0]["matrix"]).reshape(4, 4).T, matrices[0])  # column-major
    assert "matrix" not in nodes[2] and "rotation" in nodes[2]
    again = load_gltf(path)
    assert np.array_equal(again.skeleton.rest_matrices[0], matrices[0])
    assert np.array_equal(again.skeleton.rest_matrices[2], sk.rest_matrices[2])


def test_export_repairs_weights_through_check_mesh(tmp_path):
    rig = float64_rig()
    weights = rig.weights * 1.01
    # repaired by the same check_mesh where the rig is made (issue 22), so save has nothing left to repair
    with pytest.warns(UserWarning, match=r"tube: \d+ vertices have weights that do not sum to 1"):
        rig = rig.with_mesh(rig.vertices, rig.faces, rig.joints, weights, rig.attributes)
    path = save_gltf(rig, tmp_path / "tube.glb")
    np.testing.assert_allclose(load_gltf(path).weights, weights / weights.sum(axis=1, keepdims=True), rtol=1e-15)


def test_save_refuses_what_gltf_cannot_hold(tmp_path):
    rig = float64_rig()
    with pytest.raises(ModelFormatError, match=r"cannot save tube.fbx: cgaskin writes .glb, .gltf"):
        rigs.save(rig, tmp_path / "tube.fbx")
    with pytest.raises(InvalidInputError, match=r"save_gltf writes .glb or .gltf"):
        save_gltf(rig, tmp_path / "tube.obj")
    # two bones of one node (skins merged on loading) are no longer refused: a joint node is
    # added for the second, and the rig reloads with the same bones (tests/rigs/test_edges_met.py)
    shared = Skeleton(**{**rig.skeleton.__dict__, "bone_nodes": np.array([1, 1, 3])})
    again = load_gltf(save_gltf(Rig(**{**rig.__dict__, "skeleton": shared}), tmp_path / "x.glb"))
    assert np.array_equal(again.skeleton.bone_nodes, [1, 1, 3]) and again.skeleton.names == shared.names
    huge = rig.with_mesh(rig.vertices * 1e39, rig.faces, rig.joints, rig.weights)
    with pytest.raises(InvalidInputError, match=r"vertices holds values that are not finite in float32"):
        save_gltf(huge, tmp_path / "x.glb")
    bad_parents = Skeleton(**{**rig.skeleton.__dict__, "parents": np.array([-1, 2, 1, 2])})
    with pytest.raises(InvalidInputError, match=r"parents must precede their children"):
        save_gltf(Rig(**{**rig.__dict__, "skeleton": bad_parents}), tmp_path / "x.glb")


@pytest.mark.parametrize("name", MODELS)
def test_exported_skin_data_pass_the_khronos_validator_rules(models_dir, tmp_path, name):
    """What viewers read: WEIGHTS_0 summed in float32 within 2e-7 per weight (the validator's
    ACCESSOR_WEIGHTS_NON_NORMALIZED rule), no joint reused within a vertex, 0 for unused slots."""
    from cgaskin.rigs.gltf import _read_document
    rig = load_quietly(models_dir / name)
    f = _read_document(save_gltf(rig, tmp_path / "x.glb"))
    attrs = vars(f.doc.meshes[0].primitives[0].attributes)
    weights = f.accessor(attrs["WEIGHTS_0"], "")
    joints = f.accessor(attrs["JOINTS_0"], "")
    assert np.array_equal(weights, f32(rig.weights))
    total = np.zeros(len(weights), dtype=np.float32)
    for c in range(4):
        total = (total + weights[:, c].astype(np.float32)).astype(np.float32)
    assert (np.abs(total.astype(np.float64) - 1) <= 2e-7 * (weights > 0).sum(axis=1)).all()
    assert (joints[weights == 0] == 0).all()
    for row_joints, row_weights in zip(joints, weights):
        used = row_joints[row_weights > 0]
        assert len(set(used.tolist())) == len(used)


def test_weight_residuals_are_written_only_when_needed(models_dir, tmp_path):
    exact = load_quietly(models_dir / "simple_skin.gltf")  # weights 1, 0.5, ...: float32 and sum 1
    renormalised = load_quietly(models_dir / "Arm5.glb")
    for rig, expected in ((exact, False), (renormalised, True)):
        doc = pygltflib.GLTF2().load(str(save_gltf(rig, tmp_path / "x.glb")))
        (prim,) = doc.meshes[0].primitives
        # in the primitive's extras, not as vertex attributes (Blender's importer concatenates
        # application attributes of different widths and fails: tests/clients/test_blender.py)
        assert not [k for k, v in vars(prim.attributes).items() if k.startswith("_") and v is not None]
        ours = (prim.extras or {}).get("cgaskin", {})
        assert ("WEIGHTS_0_LO" in ours) == expected
        assert ("WEIGHTS_0_LO2" in ours) == expected


def test_weight_residuals_of_earlier_versions_still_load(models_dir, tmp_path):
    """Files of earlier versions hold the residuals as attributes _CGASKIN_WEIGHTS_0_LO/_LO2."""
    rig = load_quietly(models_dir / "Arm5.glb")
    doc = pygltflib.GLTF2().load(str(save_gltf(rig, tmp_path / "new.glb")))
    (prim,) = doc.meshes[0].primitives
    ours = prim.extras.pop("cgaskin")
    for name in ("LO", "LO2"):
        setattr(prim.attributes, f"_CGASKIN_WEIGHTS_0_{name}", ours[f"WEIGHTS_0_{name}"])
    doc.save(str(tmp_path / "old.glb"))
    old = load_gltf(tmp_path / "old.glb")
    assert np.array_equal(old.weights, rig.weights) and old.attributes.keys() == rig.attributes.keys()


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_application_attributes_share_one_width(tmp_path, suffix):
    """Blender imports "_NAME" attributes only when they have one width (tests/clients): a SCALAR
    _TEAR and a VEC3 _FOO are written as VEC3 (zero-padded) and reload at their own widths."""
    rig = float64_rig()
    n = rig.n_vertices
    extra = {"_TEAR": np.arange(n, dtype=np.float64)[:, None], "FOO": f32(rig.vertices * 2),
             "_PAIR": np.ones((n, 2))}
    rig = rig.with_mesh(rig.vertices, rig.faces, rig.joints, rig.weights, {**rig.attributes, **extra})
    path = save_gltf(rig, tmp_path / ("tube" + suffix))
    doc = pygltflib.GLTF2().load(str(path))
    (prim,) = doc.meshes[0].primitives
    custom = {k: doc.accessors[v].type for k, v in vars(prim.attributes).items() if k.startswith("_") and v is not None}
    assert custom == {"_TEAR": "VEC3", "_FOO": "VEC3", "_PAIR": "VEC3"}
    assert prim.extras["cgaskin"]["ATTRIBUTE_WIDTHS"] == {"_TEAR": 1, "_PAIR": 2}
    again = load_gltf(path)
    for name, values in extra.items():  # under their own names ("FOO" written as "_FOO", issue 22)
        assert np.array_equal(again.attributes[name], values)
    # one width already: written as it is, no widths recorded
    single = rig.with_mesh(rig.vertices, rig.faces, rig.joints, rig.weights, {"_TEAR": extra["_TEAR"]})
    (prim,) = pygltflib.GLTF2().load(str(save_gltf(single, tmp_path / ("one" + suffix)))).meshes[0].primitives
    assert "ATTRIBUTE_WIDTHS" not in prim.extras["cgaskin"]
    assert np.array_equal(load_gltf(tmp_path / ("one" + suffix)).attributes["_TEAR"], extra["_TEAR"])
