"""FBX/DAE loading through the assimp command line (cgaskin.rigs.assimp)."""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from cgaskin import baselines as B
from cgaskin.errors import ModelFormatError, NoSkinError
from cgaskin.rigs import assimp as A

from tests.helpers import gltf_reference as R

# assimp-converted files carry weight rows that do not sum to 1: the loader repairs them with a warning
# (checked once below, silenced elsewhere).
pytestmark = pytest.mark.filterwarnings("ignore:.*do not sum to 1:UserWarning")

needs_assimp = pytest.mark.skipif(shutil.which("assimp") is None,
                                  reason="the assimp command line tool is not installed (apt-get install assimp-utils)")


def _diag(v):
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def _fbx_files(models_dir):
    files = sorted(models_dir.glob("*.fbx"))
    if not files:
        pytest.skip(f"no .fbx files in {models_dir}")
    return files


def _rest_skin(rig):
    """Rest-pose skin of a Rig with the numpy baseline: glTF semantics, G(rest) @ IBM."""
    sk = rig.skeleton
    glob = B.global_matrices(sk.parents, sk.rest_matrices)
    return B.lbs_matrices(rig.vertices, rig.joints, rig.weights, glob[sk.bone_nodes] @ sk.inverse_bind)


def _assert_same_rig(rig, ref, tol):
    """Same mesh and skeleton; positions within tol (absolute)."""
    assert rig.n_faces == ref.n_faces and np.array_equal(rig.faces, ref.faces)
    assert rig.n_vertices == ref.n_vertices
    assert np.abs(rig.vertices - ref.vertices).max() <= tol
    sk, rk = rig.skeleton, ref.skeleton
    assert sk.n_bones == rk.n_bones
    assert [sk.names[i] for i in sk.bone_nodes] == [rk.names[i] for i in rk.bone_nodes]
    assert np.array_equal(sk.parents, rk.parents)
    assert np.abs(sk.rest_matrices - rk.rest_matrices).max() <= tol
    assert np.abs(sk.inverse_bind - rk.inverse_bind).max() <= tol
    assert np.array_equal(rig.joints, ref.joints)
    assert np.abs(rig.weights - ref.weights).max() <= 1e-12


@needs_assimp
def test_fbx_matches_shipped_glb(models_dir):
    """Each .fbx loads into the rig of the .glb shipped beside it (made by the same conversion)."""
    from cgaskin.rigs.gltf import load_gltf
    for fbx in _fbx_files(models_dir):
        glb = fbx.with_suffix(".glb")
        rig = A.load_assimp(fbx)
        assert rig.name == fbx.stem
        assert rig.vertices.dtype == np.float64 and rig.joints.shape == (rig.n_vertices, 4)
        assert np.allclose(rig.weights.sum(axis=1), 1.0, atol=1e-6)
        if not glb.exists():
            continue
        ref = load_gltf(glb)
        tol = 1e-6 * _diag(ref.vertices)
        _assert_same_rig(rig, ref, tol)
        # and its bind-pose skin is the glTF skin of the shipped file, by the independent oracle
        oracle = R.reference_skin(glb, max_influences=4)
        assert np.abs(_rest_skin(rig) - oracle).max() <= tol, fbx.name


@needs_assimp
def test_fbx_face_and_bone_counts(models_dir):
    """Counts from the models README (assimp 5.2.5, welded by the glTF exporter's JoinIdenticalVertices)."""
    expected = {"Arm5": (2935, 5037, 23), "3Cylinder4bones": (509, 758, 4), "PlaneWith3Bones": (25, 32, 3)}
    for fbx in _fbx_files(models_dir):
        if fbx.stem in expected:
            rig = A.load_assimp(fbx)
            assert (rig.n_vertices, rig.n_faces, rig.skeleton.n_bones) == expected[fbx.stem], fbx.name


@needs_assimp
def test_weight_warning_names_the_users_file(models_dir):
    fbx = models_dir / "Arm5.fbx"
    if not fbx.exists():
        pytest.skip(f"{fbx} missing")
    with pytest.warns(UserWarning, match="do not sum to 1") as record:
        A.load_assimp(fbx)
    messages = [str(w.message) for w in record]
    assert any("Arm5.fbx" in m for m in messages) and not any("cgaskin-assimp-" in m for m in messages)


@needs_assimp
def test_collada(models_dir, tmp_path):
    """A format other than FBX: a Collada file that assimp writes from the cylinder model."""
    from cgaskin.rigs.gltf import load_gltf
    src = models_dir / "3Cylinder4bones.fbx"
    if not src.exists():
        pytest.skip(f"{src} missing")
    dae = tmp_path / "cylinder.dae"
    subprocess.run(["assimp", "export", str(src), str(dae)], check=True, capture_output=True, timeout=60)
    rig = A.load_assimp(dae)
    ref = load_gltf(models_dir / "3Cylinder4bones.glb")
    assert rig.name == "cylinder"
    assert rig.n_faces == ref.n_faces and rig.skeleton.n_bones == ref.skeleton.n_bones
    tol = 1e-6 * _diag(ref.vertices)
    assert np.abs(rig.vertices - ref.vertices).max() <= tol
    assert np.abs(_rest_skin(rig) - _rest_skin(ref)).max() <= tol


@needs_assimp
def test_more_than_four_influences_keep_the_largest(models_dir, tmp_path):
    """assimp's glTF exporter keeps a vertex's *first* 4 influences; the route must keep the 4
    largest, like the glTF loader. quad_skin.glb has vertices with up to 10; through Collada."""
    from cgaskin.rigs.gltf import load_gltf
    dae = tmp_path / "quad.dae"
    subprocess.run(["assimp", "export", str(models_dir / "quad_skin.glb"), str(dae)], check=True,
                   capture_output=True, timeout=60)
    rig = A.load_assimp(dae)
    with pytest.warns(UserWarning, match="more than 4 bone influences"):
        ref = load_gltf(models_dir / "quad_skin.glb")

    def by_bone_name(r):
        names = [r.skeleton.names[i] for i in r.skeleton.bone_nodes]
        return [dict(sorted((names[j], float(w)) for j, w in zip(js, ws) if w > 0))
                for js, ws in zip(r.joints, r.weights)]
    assert rig.n_vertices == ref.n_vertices == 4
    for got, expected in zip(by_bone_name(rig), by_bone_name(ref)):
        assert list(got) == list(expected)                           # the same 4 bones
        np.testing.assert_allclose(list(got.values()), list(expected.values()), atol=1e-6)


def _corrupt_files(models_dir, tmp_path):
    fbx = _fbx_files(models_dir)[0]
    data = fbx.read_bytes()
    rng = np.random.default_rng(0)
    files = {
        "truncated": data[: len(data) // 3],
        "header-only": data[:200],
        "garbage": rng.integers(0, 256, 4096, dtype=np.uint8).tobytes(),
        "empty": b"",
        "text": b"hello, this is not a model\n",
    }
    out = []
    for name, content in files.items():
        p = tmp_path / f"{name}.fbx"
        p.write_bytes(content)
        out.append(p)
    return out


@needs_assimp
def test_corrupt_fbx_raises(models_dir, tmp_path):
    for path in _corrupt_files(models_dir, tmp_path):
        with pytest.raises(ModelFormatError) as info:
            A.load_assimp(path)
        message = str(info.value)
        assert str(path.resolve()) in message and "assimp" in message, message


@needs_assimp
def test_missing_file(tmp_path):
    with pytest.raises(ModelFormatError, match="no such file"):
        A.load_assimp(tmp_path / "nope.fbx")


@needs_assimp
def test_rigid_mesh_loads_as_a_rigid_bone(tmp_path):
    """A static OBJ has no skin: it loads as one rigid bone (tests/rigs/test_skinless.py has more)."""
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    rig = A.load_assimp(obj)
    assert rig.name == "tri" and rig.n_faces == 1 and rig.skeleton.n_bones == 1
    np.testing.assert_array_equal(rig.vertices[rig.faces[0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


@needs_assimp
def test_file_without_a_mesh_names_the_users_file(tmp_path):
    """assimp reads it fine, but it holds no mesh: the glTF loader's NoSkinError comes through
    naming the user's file, not the temporary one."""
    obj = tmp_path / "points.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    with pytest.raises(NoSkinError, match="holds no triangle mesh") as info:
        A.load_assimp(obj)
    assert "points.obj" in str(info.value) and "cgaskin-assimp-" not in str(info.value)


def test_cannot_read_lists_what_this_assimp_reads(tmp_path, monkeypatch):
    def fake_run(cmd, **kwargs):
        if cmd[1] == "listext":
            return subprocess.CompletedProcess(cmd, 0, stdout="*.3ds;*.fbx;*.glb;*.obj\n", stderr="")
        return subprocess.CompletedProcess(cmd, 10, stdout="ERROR: Failed to load file: No suitable reader", stderr="")

    model = tmp_path / "m.abc"
    model.write_bytes(b"x")
    monkeypatch.setattr(A.subprocess, "run", fake_run)
    monkeypatch.setattr(A, "_FORMATS", {})
    with pytest.raises(ModelFormatError, match=r"m.abc: assimp cannot read this file \(exit status 10\): "
                                               r"ERROR: Failed to load file: No suitable reader \(cgaskin reads "
                                               r"glTF, .glb and .gltf, natively and every other format through "
                                               r"assimp; this assimp reads .3ds .fbx .obj\)"):
        A.load_assimp(model, executable="fake-assimp")


def test_missing_executable_says_how_to_install(tmp_path, monkeypatch):
    model = tmp_path / "x.fbx"
    model.write_bytes(b"x")
    monkeypatch.setattr(A.shutil, "which", lambda name: None)
    with pytest.raises(ModelFormatError, match="apt-get install assimp-utils"):
        A.load_assimp(model)
    with pytest.raises(ModelFormatError, match="apt-get install assimp-utils"):
        A.load_assimp(model, executable=str(tmp_path / "no-such-assimp"))


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX shell script")
def test_timeout(tmp_path):
    slow = tmp_path / "slow-assimp"
    slow.write_text("#!/bin/sh\nsleep 10\n")
    slow.chmod(0o755)
    model = tmp_path / "x.fbx"
    model.write_bytes(b"x")
    with pytest.raises(ModelFormatError, match="did not finish"):
        A.load_assimp(model, timeout=0.5, executable=str(slow))


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX shell script")
def test_exit_zero_without_output_is_an_error(tmp_path):
    fake = tmp_path / "fake-assimp"
    fake.write_text("#!/bin/sh\necho 'nothing written'\n")
    fake.chmod(0o755)
    model = tmp_path / "x.fbx"
    model.write_bytes(b"x")
    with pytest.raises(ModelFormatError, match="nothing written"):
        A.load_assimp(model, executable=str(fake))


def test_path_like_and_dash_names(tmp_path, monkeypatch):
    """A file named like an option reaches assimp as an absolute path, not as a flag."""
    seen = {}

    def fake_run(cmd, **kwargs):
        seen.setdefault("cmd", cmd)        # the export (a "listext" may follow its failure)
        return subprocess.CompletedProcess(cmd, 1, stdout="ERROR: Failed to load file: nope", stderr="")

    model = tmp_path / "-cfull.fbx"
    model.write_bytes(b"x")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(A.subprocess, "run", fake_run)
    with pytest.raises(ModelFormatError, match="Failed to load file: nope"):
        A.load_assimp(os.path.join(".", "-cfull.fbx"), executable="assimp")
    assert seen["cmd"][2] == str(model.resolve())
    assert seen["cmd"][4] == "-fglb2"
