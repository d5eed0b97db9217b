"""Issue 22: files and rigs at the edges of the loader and saver.

Two skins sharing joint nodes save and reload; a broken animation is dropped, not the model; a
deeply nested JSON, /dev/null and other special files are format errors; attributes round-trip
with their names and values; assimp-loaded files warn about dropped influences as glTF files do.
"""
import json
import os
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import cgaskin
from cgaskin.errors import ModelFormatError
from cgaskin.rigs.gltf import load_gltf

from tests.helpers import gltf_reference as R
from tests.helpers.gltf_files import Gltf

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _cli(*argv):
    """Run ``python -m cgaskin`` in a fresh process: (exit status, stdout + stderr)."""
    proc = subprocess.run([sys.executable, "-m", "cgaskin", *map(str, argv)], cwd=REPO,
                          capture_output=True, text=True, timeout=600)
    return proc.returncode, proc.stdout + proc.stderr


def _quiet_load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return cgaskin.load(path)


# --- item 4: two skins that share joint nodes -----------------------------------------------------

def _column_major(matrices):
    return np.array([np.asarray(m, dtype=float).T.reshape(16) for m in matrices])


def _translation(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def two_skins_sharing_joints() -> Gltf:
    """The quad skinned to joints A, B (identity inverse bind matrices) and a second quad skinned
    by a second skin to the same joints with other inverse bind matrices, and a clip."""
    g = Gltf.quad()
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float) * 0.5 + [0, 1, 0]
    weights = np.array([[1, 0, 0, 0], [0.6, 0.4, 0, 0], [0.3, 0.7, 0, 0], [0, 1, 0, 0]])
    g.doc["meshes"].append({"primitives": [{"attributes": {
        "POSITION": g.accessor(positions, 5126, "VEC3", min=positions.min(0).tolist(),
                               max=positions.max(0).tolist()),
        "JOINTS_0": g.accessor([[1, 0, 0, 0]] * 4, 5121, "VEC4"),   # slots swapped: B, A
        "WEIGHTS_0": g.accessor(weights, 5126, "VEC4")},
        "indices": g.accessor([0, 1, 2, 0, 2, 3], 5123, "SCALAR")}]})
    ibm = g.accessor(_column_major([_translation(0.25, -1, 0.5), _translation(-0.5, -1.5, 0)]), 5126, "MAT4")
    g.doc["skins"].append({"joints": [2, 1], "inverseBindMatrices": ibm})
    g.doc["nodes"].append({"name": "quad2", "mesh": 1, "skin": 1})
    g.doc["scenes"][0]["nodes"].append(4)
    times = g.accessor([0.0, 1.0], 5126, "SCALAR", min=[0.0], max=[1.0])
    half = np.sin(0.6 / 2)
    rotations = g.accessor([[0, 0, 0, 1], [0, 0, half, np.cos(0.6 / 2)]], 5126, "VEC4")
    moves = g.accessor([[0.5, 0, 0], [0.5, 0.3, -0.2]], 5126, "VEC3")
    g.doc["animations"] = [{"name": "bend", "samplers": [
        {"input": times, "output": rotations}, {"input": times, "output": moves}],
        "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}},
                     {"sampler": 1, "target": {"node": 2, "path": "translation"}}]}]
    return g


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_two_skins_sharing_joints_save_and_reload_skinning_the_same(tmp_path, suffix):
    source = two_skins_sharing_joints().write(tmp_path / "two_skins.gltf")
    rig = load_gltf(source)
    assert rig.skeleton.n_bones == 4 and len(np.unique(rig.skeleton.bone_nodes)) == 2
    saved = cgaskin.save(rig, tmp_path / f"saved{suffix}")
    back = load_gltf(saved)
    assert back.skeleton.names == rig.skeleton.names
    assert np.array_equal(back.skeleton.bone_nodes, rig.skeleton.bone_nodes)
    assert np.array_equal(back.skeleton.inverse_bind, rig.skeleton.inverse_bind)
    assert np.array_equal(back.joints, rig.joints) and np.array_equal(back.weights, rig.weights)
    for time in (None, 0.0, 0.4, 1.0):
        pose = (lambda r: r.rest_pose()) if time is None else (lambda r: r.pose("bend", time))
        expected = R.reference_skin(source, None if time is None else 0, time or 0.0)
        ours = cgaskin.skin(rig, pose(rig))
        np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-6)
        assert np.array_equal(cgaskin.skin(back, pose(back)), ours)
        # what another reader (the spec, as three.js and Blender read it) makes of the saved file
        np.testing.assert_allclose(R.reference_skin(saved, None if time is None else 0, time or 0.0),
                                   ours, rtol=0, atol=1e-6)


def test_cut_of_two_skins_sharing_joints_exits_0(tmp_path):
    source = two_skins_sharing_joints().write(tmp_path / "two_skins.glb")
    code, output = _cli("cut", source, "--normal", 1, 0, 0, "--point", 0.3, 0, 0, "--clip", "bend",
                        "--time", 0.5, "--out", tmp_path / "a.glb", tmp_path / "b.glb")
    assert code == 0, output
    for half in ("a.glb", "b.glb"):
        assert _quiet_load(tmp_path / half).n_faces > 0


# --- item 6: a broken animation is dropped, the model loads -------------------------------------

def test_clip_with_non_finite_key_times_is_dropped_with_a_warning_naming_it(tmp_path):
    g = two_skins_sharing_joints()
    good = g.doc["animations"][0]
    times = g.accessor([0.0, np.inf], 5126, "SCALAR", min=[0.0], max=[0.0])
    broken = {"name": "broken walk", "samplers": [{"input": times, "output": good["samplers"][0]["output"]}],
              "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}]}
    g.doc["animations"] = [broken, good]
    path = g.write(tmp_path / "broken_clip.glb")
    with pytest.warns(UserWarning, match=r"broken_clip.glb: dropped animation 0 \('broken walk'\): .*key "
                                         r"times hold non-finite values"):
        rig = load_gltf(path)
    assert [clip.name for clip in rig.clips] == ["bend"]
    assert rig.n_faces == 4 and rig.skeleton.n_bones == 4
    np.testing.assert_allclose(cgaskin.skin(rig, rig.pose("bend", 0.5)), R.reference_skin(path, 1, 0.5),
                               rtol=0, atol=1e-6)


# --- item 7 and 13: what the path is when it is no model --------------------------------------------

def test_deeply_nested_json_is_a_format_error(tmp_path):
    path = tmp_path / "deep.gltf"
    path.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(ModelFormatError, match=r"deep.gltf: the glTF JSON nests arrays/objects deeper"):
        cgaskin.load(path)
    code, output = _cli("skin", path, "--out", tmp_path / "x.glb")
    assert code == 2, output
    assert output.strip().count("\n") == 0 and "deep.gltf: the glTF JSON nests" in output, output
    assert "Traceback" not in output


@pytest.mark.parametrize("path", ["/dev/null", "/dev/zero"])
def test_a_device_is_not_a_model_file(path):
    with pytest.raises(ModelFormatError, match=r"is not a regular file but a character device") as info:
        cgaskin.load(path)
    assert "no such file" not in str(info.value)


@pytest.mark.parametrize("name", ["pipe.glb", "pipe.fbx"])
def test_a_named_pipe_is_not_a_model_file(tmp_path, name):
    os.mkfifo(tmp_path / name)   # reading it would block forever
    with pytest.raises(ModelFormatError, match=r"is not a regular file but a named pipe"):
        cgaskin.load(tmp_path / name)


def test_an_empty_gltf_says_so(tmp_path):
    (tmp_path / "empty.glb").write_bytes(b"")
    with pytest.raises(ModelFormatError, match=r"empty.glb: the file is empty"):
        cgaskin.load(tmp_path / "empty.glb")


# --- item 14: attributes round-trip with their names and values -----------------------------------

#: names of every kind: glTF semantics at the spec's widths (or not), application-specific ones,
#: plain ones whose "_" form another attribute holds, names of other parts of a primitive
NAMES = ["NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1", "TEXCOORD_7", "COLOR_0", "COLOR_1", "FOO",
         "_FOO", "_FOO_2", "foo", "POSITION", "JOINTS_0", "WEIGHTS_1", "TEXCOORD_01", "_TEAR", "my attr",
         "CGASKIN_WEIGHTS_0_LO", "_CGASKIN_WEIGHTS_0_LO"]


@st.composite
def attribute_sets(draw, n):
    """{name: (n, width) or (n,) float32-exact float64 values} of 1..6 attributes."""
    names = draw(st.lists(st.sampled_from(NAMES) | st.from_regex(r"_?[A-Za-z][A-Za-z0-9_ ]{0,8}", fullmatch=True),
                          min_size=1, max_size=6, unique=True))
    out = {}
    for name in names:
        width = draw(st.sampled_from([1, 2, 3, 4]))
        rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
        scale = 10.0 ** draw(st.integers(-6, 6))
        out[name] = (rng.standard_normal((n, width)) * scale).astype(np.float32).astype(np.float64)
        if width == 1 and draw(st.booleans()):
            out[name] = out[name][:, 0]
    return out


ARM = cgaskin.capsule_arm()


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                 HealthCheck.too_slow])
@given(data=st.data())
def test_attributes_round_trip_with_names_and_values(tmp_path_factory, data):
    arm = ARM
    attributes = data.draw(attribute_sets(arm.n_vertices))
    rig = arm.with_mesh(arm.vertices, arm.faces, arm.joints, arm.weights, attributes)
    suffix = data.draw(st.sampled_from([".glb", ".gltf"]))
    path = tmp_path_factory.mktemp("attributes") / f"a{suffix}"
    cgaskin.save(rig, path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # no attribute is dropped, silently or not
        back = cgaskin.load(path)
    assert sorted(back.attributes) == sorted(attributes)
    for name, values in attributes.items():
        assert np.array_equal(back.attributes[name], values.reshape(len(values), -1)), name
    # and what other readers see is valid glTF: spec semantics or "_" names only
    doc = json.loads(path.read_text()) if suffix == ".gltf" else None
    if doc is not None:
        for name in doc["meshes"][0]["primitives"][0]["attributes"]:
            assert name.startswith("_") or name.split("_")[0] in (
                "POSITION", "NORMAL", "TANGENT", "TEXCOORD", "COLOR", "JOINTS", "WEIGHTS"), name


def _quad_with(g: Gltf, **attributes) -> Gltf:
    g.primitive["attributes"].update(attributes)
    return g


def test_loader_reads_tangent_texcoord_n_and_color_n_per_spec(tmp_path):
    g = Gltf.quad()
    tangent = [[1, 0, 0, 1], [0, 1, 0, -1], [0, 0, 1, 1], [1, 0, 0, -1]]
    uv1 = [[0, 0], [255, 0], [255, 255], [0, 128]]          # normalized unsigned byte
    rgb = [[0.5, 0.25, 1.0]] * 4                             # VEC3 float
    rgba = [[65535, 0, 32768, 65535]] * 4                    # VEC4 normalized unsigned short
    _quad_with(g, TANGENT=g.accessor(tangent, 5126, "VEC4"),
               TEXCOORD_1=g.accessor(uv1, 5121, "VEC2", normalized=True),
               COLOR_0=g.accessor(rgb, 5126, "VEC3"),
               COLOR_1=g.accessor(rgba, 5123, "VEC4", normalized=True))
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert sorted(rig.attributes) == ["COLOR_0", "COLOR_1", "TANGENT", "TEXCOORD_1"]
    np.testing.assert_array_equal(rig.attributes["TANGENT"], tangent)
    np.testing.assert_array_equal(rig.attributes["TEXCOORD_1"], np.array(uv1) / 255.0)
    np.testing.assert_array_equal(rig.attributes["COLOR_0"], np.float32(rgb))
    np.testing.assert_array_equal(rig.attributes["COLOR_1"], np.array(rgba) / 65535.0)
    back = load_gltf(cgaskin.save(rig, tmp_path / "back.glb"))
    for name, values in rig.attributes.items():
        np.testing.assert_array_equal(back.attributes[name], np.float32(values), err_msg=name)


def test_loader_refuses_a_color_of_the_wrong_type_and_warns_about_unknown_attributes(tmp_path):
    g = Gltf.quad()
    _quad_with(g, COLOR_0=g.accessor([[1, 2]] * 4, 5126, "VEC2"))
    with pytest.raises(ModelFormatError, match=r"COLOR_0 must be VEC3/VEC4 of floats or normalized integers"):
        load_gltf(g.write(tmp_path / "q.glb"))
    g = Gltf.quad()
    _quad_with(g, TEMPERATURE=g.accessor([1, 2, 3, 4], 5126, "SCALAR"))
    with pytest.warns(UserWarning, match=r"ignored attributes 'TEMPERATURE': they are no glTF 2.0 semantic"):
        rig = load_gltf(g.write(tmp_path / "r.glb"))
    assert rig.attributes == {}


# --- items 5 and 6 through assimp: influences beyond 4, animations with 0 ticks per second -------

needs_assimp = pytest.mark.skipif(shutil.which("assimp") is None,
                                  reason="the assimp command line tool is not installed (apt-get install assimp-utils)")

#: six bones in a chain, each weighted to all four vertices of a quad with these weights
SIX_WEIGHTS = [0.3, 0.2, 0.15, 0.15, 0.1, 0.1]


def _x_matrix(y=0.0):
    return f"1.0,0.0,0.0,0.0,0.0,1.0,0.0,0.0,0.0,0.0,1.0,0.0,0.0,{y:.6f},0.0,1.0;;"


def directx_six_bones(ticks_per_second) -> str:
    """A DirectX .x text file: a quad with 6 influences per vertex on a 6-bone chain and one
    animation 'Walk' (keys at ticks 0 and 10) of bone B1; ``AnimTicksPerSecond`` as given, or
    absent for None."""
    frames = ""
    for i in reversed(range(6)):
        frames = f"Frame B{i} {{\n FrameTransformMatrix {{ {_x_matrix(0.2 if i else 0.0)} }}\n{frames}}}\n"
    skins = "".join(f'SkinWeights {{\n "B{i}";\n 4;\n 0,1,2,3;\n {w},{w},{w},{w};\n {_x_matrix(-0.2 * i)}\n}}\n'
                    for i, w in enumerate(SIX_WEIGHTS))
    ticks = "" if ticks_per_second is None else f"AnimTicksPerSecond {{\n {ticks_per_second};\n}}\n"
    return f"""xof 0303txt 0032
{ticks}
Frame Root {{
 FrameTransformMatrix {{ {_x_matrix()} }}
 {frames}
 Mesh quad {{
  4;
  0.0;0.0;0.0;,
  1.0;0.0;0.0;,
  1.0;1.0;0.0;,
  0.0;1.0;0.0;;
  2;
  3;0,1,2;,
  3;0,2,3;;
  XSkinMeshHeader {{ 6; 6; 6; }}
  {skins}
 }}
}}
AnimationSet Walk {{
 Animation {{
  {{B1}}
  AnimationKey {{
   0;
   2;
   0;4;1.0,0.0,0.0,0.0;;,
   10;4;0.7071,0.0,0.0,0.7071;;;
  }}
 }}
}}
"""


INFLUENCE_WARNING = r"4 vertices have more than 4 bone influences \(up to 6\); kept the 4 largest weights"


@needs_assimp
def test_assimp_file_with_six_influences_warns_as_gltf_files_do(tmp_path):
    path = tmp_path / "six.x"
    path.write_text(directx_six_bones(25))
    with pytest.warns(UserWarning, match=r"six.x: " + INFLUENCE_WARNING):
        rig = cgaskin.load(path)
    kept = np.array(SIX_WEIGHTS[:4]) / sum(SIX_WEIGHTS[:4])
    np.testing.assert_allclose(np.sort(rig.weights, axis=1)[:, ::-1], np.tile(kept, (4, 1)), atol=1e-7)
    # the glTF loader's warning, word for word, for a glTF file with the same 6 influences
    g = Gltf.quad()
    g.doc["skins"][0]["joints"] = [1, 2, 0, 3, 4, 5]
    g.doc["nodes"] += [{"name": f"C{i}"} for i in range(2)]
    g.doc["nodes"][0]["children"] = [1, 4, 5]
    g.doc["nodes"][3]["skin"] = 0
    g.primitive["attributes"]["JOINTS_0"] = g.accessor([[0, 1, 2, 3]] * 4, 5121, "VEC4")
    g.primitive["attributes"]["WEIGHTS_0"] = g.accessor([SIX_WEIGHTS[:4]] * 4, 5126, "VEC4")
    g.primitive["attributes"]["JOINTS_1"] = g.accessor([[4, 5, 0, 0]] * 4, 5121, "VEC4")
    g.primitive["attributes"]["WEIGHTS_1"] = g.accessor([SIX_WEIGHTS[4:] + [0, 0]] * 4, 5126, "VEC4")
    with pytest.warns(UserWarning, match=r"six.glb: " + INFLUENCE_WARNING):
        load_gltf(g.write(tmp_path / "six.glb"))


@needs_assimp
@pytest.mark.filterwarnings("ignore:.*more than 4 bone influences:UserWarning")
@pytest.mark.parametrize("ticks", [0, None])
def test_directx_animation_without_ticks_per_second_plays_at_25(tmp_path, ticks):
    """assimp converts its keys to NaN/inf times; cgaskin plays it as assimp's viewer does."""
    reference = tmp_path / "ticks25.x"
    reference.write_text(directx_six_bones(25))
    broken = tmp_path / "ticks0.x"
    broken.write_text(directx_six_bones(ticks))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        expected = cgaskin.load(reference)
    with pytest.warns(UserWarning, match=r"ticks0.x: animation 'Walk' gives 0 ticks per second \(or none\): "
                                         r"played at 25 ticks per second"):
        rig = cgaskin.load(broken)
    assert [clip.name for clip in rig.clips] == ["Walk"] and rig.clips[0].duration == pytest.approx(0.4)
    assert np.array_equal(rig.vertices, expected.vertices) and rig.skeleton.names == expected.skeleton.names
    for time in (0.0, 0.13, 0.4):
        skinned = cgaskin.skin(rig, rig.pose("Walk", time))
        assert np.array_equal(skinned, cgaskin.skin(expected, expected.pose("Walk", time)))
    assert not np.allclose(cgaskin.skin(rig, rig.pose("Walk", 0.4)), cgaskin.skin(rig, rig.pose("Walk", 0.0)))


@needs_assimp
def test_collada_of_a_model_with_ten_influences_warns_as_its_gltf_does(models_dir, tmp_path):
    """quad_skin.glb (up to 10 influences) and its Collada conversion read through assimp: one
    warning, word for word the same but for the file name."""
    dae = tmp_path / "quad_skin.dae"
    subprocess.run(["assimp", "export", str(models_dir / "quad_skin.glb"), str(dae)], check=True,
                   capture_output=True, timeout=60)

    def influence_warnings(path):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            cgaskin.load(path)
        return [str(w.message).split(": ", 1)[1] for w in caught if "bone influences" in str(w.message)]

    expected = influence_warnings(models_dir / "quad_skin.glb")
    assert expected == ["3 vertices have more than 4 bone influences (up to 10); kept the 4 largest "
                        "weights of each and renormalised"]
    assert influence_warnings(dae) == expected
