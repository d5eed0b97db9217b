"""glTF loader on the real models: counts, clips, skeleton structure, influences beyond four, weights
to renormalise, matrix nodes.
"""
import warnings

import numpy as np
import pytest

from cgaskin import rigs
from cgaskin.rigs.gltf import load_gltf, trs_to_matrix

from tests.helpers.gltf_files import assert_valid_rig, load_quietly


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
