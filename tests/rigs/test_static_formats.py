"""Static formats (OBJ, PLY, STL, OFF, ZAE) through assimp load as rigs without a skin (issue 10, "any
model a user has"): every format assimp reads, none refused by its extension; files assimp cannot read
give a ModelFormatError that says how cgaskin reads models.
"""
import shutil
import subprocess
import warnings
import zipfile

import numpy as np
import pytest

import cgaskin
from cgaskin.errors import ModelFormatError

from tests.helpers.cut_checks import volume
from tests.helpers.gltf_files import assert_valid_rig

needs_assimp = pytest.mark.skipif(shutil.which("assimp") is None,
                                  reason="the assimp command line tool is not installed (apt-get install assimp-utils)")


def _same_point_sets(got, expected, tol):
    from scipy.spatial import cKDTree
    assert cKDTree(expected).query(got)[0].max() <= tol
    assert cKDTree(got).query(expected)[0].max() <= tol


@needs_assimp
@pytest.mark.parametrize("suffix", [".obj", ".ply", ".stl"])
def test_static_formats_through_assimp(tmp_path, suffix):
    import trimesh
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.apply_transform(np.diag([2.0, 1.0, 0.5, 1.0]))
    mesh.apply_translation([1, 2, 3])
    path = tmp_path / f"scan{suffix}"
    mesh.export(path)
    rig = cgaskin.load(path)
    assert_valid_rig(rig)
    assert rig.name == "scan" and rig.skeleton.n_bones == 1 and (rig.weights[:, 0] == 1).all()
    v = np.asarray(mesh.vertices)
    _same_point_sets(rig.vertices, v, 1e-6 * np.linalg.norm(np.ptp(v, axis=0)))
    assert rig.n_faces == len(mesh.faces)
    np.testing.assert_allclose(volume(rig.vertices, rig.faces), mesh.volume, rtol=1e-5)   # outward
    np.testing.assert_allclose(cgaskin.skin(rig, rig.rest_pose()), rig.vertices, atol=1e-12)
    halves = cgaskin.cut(rig, [1, 0, 0], [1, 2, 3], cap=True)
    assert all(h.n_faces > 0 for h in halves)


@needs_assimp
@pytest.mark.parametrize("suffix, content", [
    (".obj", b"v 0 0 0\nv 1 0 0\nf 1 2 7 9\nthis is not obj\n"),
    (".ply", b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n"),
    (".stl", b"\x00" * 40),
    (".xyz", b"hello, this is not a model\n"),
    ("", b"no extension at all\n"),
])
def test_bad_files_through_assimp(tmp_path, suffix, content):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(content)
    with pytest.raises(ModelFormatError) as info:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cgaskin.load(path)
    message = str(info.value)
    assert "bad" in message and "cgaskin-assimp-" not in message


@needs_assimp
def test_unknown_format_says_how_cgaskin_reads(tmp_path):
    path = tmp_path / "model.xyz"
    path.write_text("hello\n")
    with pytest.raises(ModelFormatError) as info:
        cgaskin.load(path)
    message = str(info.value)
    assert str(path) in message and "assimp cannot read this file" in message
    assert "natively and every other format through assimp" in message and ".fbx" in message


@needs_assimp
def test_formats_outside_the_old_list(tmp_path):
    """.off and .zae (zipped Collada) were refused by extension before; assimp reads them."""
    src = tmp_path / "tet.obj"
    src.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    off = tmp_path / "tet.off"
    off.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    dae = tmp_path / "tet.dae"
    subprocess.run(["assimp", "export", str(src), str(dae), "-fcollada"], check=True, capture_output=True, timeout=60)
    zae = tmp_path / "tet.zae"
    with zipfile.ZipFile(zae, "w") as z:
        z.write(dae, "tet.dae")
        z.writestr("manifest.xml", '<?xml version="1.0" encoding="utf-8"?><dae_root>./tet.dae</dae_root>')
    for path in (src, off, zae):
        rig = cgaskin.load(path)
        assert rig.n_faces == 4
        np.testing.assert_allclose(volume(rig.vertices, rig.faces), 1 / 6, rtol=1e-6)
