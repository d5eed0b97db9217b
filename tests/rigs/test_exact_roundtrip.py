"""A float64 rig survives save and load exactly, posed too (issue 10, item 1, the posed half).

glTF stores inverse bind matrices and keyframes as float32: a rig built in float64 (the capsule
arm, a clip made by clip_from_poses, an edited skeleton) reloaded with slightly different ones, so
a posed surface moved by ~1e-7 and a posed tear stroke that continues the previous one missed the
slit's end. save_gltf writes their rounding residuals in the skin's and the samplers' extras."""
from __future__ import annotations

import dataclasses

import numpy as np
import pygltflib
import pytest

import cgaskin
from cgaskin import Channel, Clip, clip_from_poses, tear_stroke
from cgaskin.errors import ModelFormatError
from cgaskin.rigs.gltf import _read_document

from tests.helpers.tear_checks import capsule_blades

TIMES = [0.0, 0.2, 0.37, 0.5, 0.61, 0.9, 1.1, 1.7, 2.5]


def f32(a):
    return np.asarray(a, dtype=np.float64).astype(np.float32).astype(np.float64)


def float64_arm():
    """The capsule arm with a clip_from_poses clip (rotation and dilation, times 0.37 and 1.1) and a
    bind matrix edited to a value that float32 cannot hold."""
    rig = cgaskin.capsule_arm()
    rest = rig.rest_pose()
    bent = rest.rotate("elbow", [0, 0, 1], 0.4).dilate("wrist", 1.3)
    nod = clip_from_poses("nod", [0.0, 0.37, 1.1], [rest, bent, rest.dilate("elbow", 0.8)])
    ibm = np.array(rig.skeleton.inverse_bind)
    ibm[2, 0, 3] += 1e-7 / 3
    skeleton = dataclasses.replace(rig.skeleton, inverse_bind=ibm)
    return dataclasses.replace(rig, skeleton=skeleton).with_clips(nod)


def reloaded(rig, folder, suffix, name="arm"):
    return cgaskin.load(cgaskin.save(rig, folder / (name + suffix)))


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_float64_bind_matrices_and_keyframes_reload_bit_identical(tmp_path, suffix):
    rig = float64_arm()
    assert not np.array_equal(rig.skeleton.inverse_bind, f32(rig.skeleton.inverse_bind))
    assert not all(np.array_equal(ch.times, f32(ch.times)) and np.array_equal(ch.values, f32(ch.values))
                   for clip in rig.clips for ch in clip.channels)
    back = reloaded(rig, tmp_path, suffix)
    assert np.array_equal(back.skeleton.inverse_bind, rig.skeleton.inverse_bind)
    for a, b in zip(rig.clips, back.clips, strict=True):
        for x, y in zip(a.channels, b.channels, strict=True):
            assert np.array_equal(y.times, x.times) and np.array_equal(y.values, x.values)
    for clip in ("wave", "nod"):
        for t in TIMES:
            assert np.array_equal(cgaskin.skin(back, back.pose(clip, t)), cgaskin.skin(rig, rig.pose(clip, t)))
    # other readers see the float32 roundings; the residuals are in the extras
    f = _read_document(tmp_path / ("arm" + suffix))
    skin = f.doc.skins[0]
    stored = f.accessor(skin.inverseBindMatrices, "")
    assert np.array_equal(stored, f32(rig.skeleton.inverse_bind))
    assert set(skin.extras["cgaskin"]) == {"INVERSE_BIND_LO", "INVERSE_BIND_LO2"}
    nod = next(a for a in f.doc.animations if a.name == "nod")
    assert all({"INPUT_LO", "INPUT_LO2"} <= set(s.extras["cgaskin"]) for s in nod.samplers)


def test_residuals_follow_shared_key_times(tmp_path):
    """Samplers with the same float64 times share one input and its residuals; times that round to
    the same float32 but differ in float64 get their own."""
    rig = cgaskin.capsule_arm()
    t = np.array([0.05, 0.1, 0.3, 0.7])
    t_next = np.nextafter(t, 1.0)
    assert np.array_equal(f32(t_next), f32(t)) and not np.array_equal(t_next, t)
    q = np.tile([0.0, 0.0, np.sin(0.1), np.cos(0.1)], (4, 1))
    clip = Clip("shared", (Channel(0, "rotation", "LINEAR", t, q),
                           Channel(1, "translation", "LINEAR", t_next, np.linspace(0, 1 / 3, 12).reshape(4, 3)),
                           Channel(2, "scale", "STEP", t.copy(), np.full((4, 3), 1.25)),
                           Channel(1, "scale", "LINEAR", f32(t), np.ones((4, 3)))))
    rig = rig.with_clips(clip)
    back = reloaded(rig, tmp_path, ".glb")
    for x, y in zip(rig.clips[-1].channels, back.clips[-1].channels, strict=True):
        assert np.array_equal(y.times, x.times) and np.array_equal(y.values, x.values)
    doc = pygltflib.GLTF2().load(str(tmp_path / "arm.glb"))
    s = doc.animations[-1].samplers
    inputs = [(x.input, {k: v for k, v in x.extras.get("cgaskin", {}).items() if k.startswith("INPUT")})
              for x in s]
    assert inputs[0] == inputs[2] and set(inputs[0][1]) == {"INPUT_LO", "INPUT_LO2"}
    assert inputs[1][0] != inputs[0][0] and inputs[1][1]["INPUT_LO"] != inputs[0][1]["INPUT_LO"]
    assert s[3].extras == {}  # float32 times and values: nothing to add
    assert "OUTPUT_LO" in s[1].extras["cgaskin"] and "OUTPUT_LO" not in s[2].extras["cgaskin"]


def test_files_without_residuals_load_the_float32_values(models_dir, tmp_path):
    fox = cgaskin.load(models_dir / "Fox.glb")
    doc = pygltflib.GLTF2().load(str(models_dir / "Fox.glb"))
    acc = doc.accessors[doc.skins[0].inverseBindMatrices]
    view = doc.bufferViews[acc.bufferView]
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    raw = np.frombuffer(doc.binary_blob(), "<f4", acc.count * 16, start).reshape(-1, 4, 4)
    assert np.array_equal(fox.skeleton.inverse_bind, raw.transpose(0, 2, 1)[:len(doc.skins[0].joints)])
    for clip in fox.clips:
        for ch in clip.channels:
            assert np.array_equal(ch.times, f32(ch.times)) and np.array_equal(ch.values, f32(ch.values))
    # and cgaskin writes no residuals for them
    saved = pygltflib.GLTF2().load(str(cgaskin.save(fox, tmp_path / "fox.glb")))
    assert "cgaskin" not in saved.skins[0].extras
    assert all("cgaskin" not in s.extras for a in saved.animations for s in a.samplers)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
@pytest.mark.parametrize("clip, t", [("wave", 0.5), ("nod", 0.61)])
def test_a_posed_slit_continues_after_save_and_load(tmp_path, suffix, clip, t):
    rig = float64_arm()
    a, b = capsule_blades(0.2, 0.45)
    c = capsule_blades(0.45, 0.7)[1]
    torn = tear_stroke(rig, a, b, pose=rig.pose(clip, t)).rig
    back = reloaded(torn, tmp_path, suffix, "torn")
    here = tear_stroke(torn, b, c, pose=torn.pose(clip, t))
    there = tear_stroke(back, b, c, pose=back.pose(clip, t))
    assert here.split[0] and here.kinds[0] == 0            # in memory: the slit goes on from its end
    assert there.split[0] and there.kinds[0] == 0          # and so it does after save and load
    np.testing.assert_array_equal(there.kinds, here.kinds)
    np.testing.assert_array_equal(there.points, here.points)
    np.testing.assert_array_equal(there.rig.faces, here.rig.faces)
    np.testing.assert_array_equal(there.rig.vertices, here.rig.vertices)


def _corrupt(path, folder, edit):
    doc = pygltflib.GLTF2().load(str(path))
    edit(doc)
    doc.save(str(folder / "bad.glb"))
    return folder / "bad.glb"


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.skins[0].extras["cgaskin"].update(INVERSE_BIND_LO=999),
     r"skin 0 extras\.cgaskin\.INVERSE_BIND_LO accessor = 999 is out of range"),
    (lambda d: d.skins[0].extras["cgaskin"].update(INVERSE_BIND_LO2="3"),
     r"skin 0 extras\.cgaskin\.INVERSE_BIND_LO2 must be an accessor index, got '3'"),
    (lambda d: d.skins[0].extras["cgaskin"].update(INVERSE_BIND_LO=d.animations[0].samplers[0].input),
     r"skin 0 extras\.cgaskin\.INVERSE_BIND_LO must be finite floats shaped like INVERSE_BIND"),
    (lambda d: d.animations[-1].samplers[0].extras["cgaskin"].update(INPUT_LO=True),
     r"sampler 0 extras\.cgaskin\.INPUT_LO must be an accessor index, got True"),
    (lambda d: d.animations[-1].samplers[0].extras["cgaskin"].update(OUTPUT_LO2=-1),
     r"sampler 0 extras\.cgaskin\.OUTPUT_LO2 accessor = -1 is out of range"),
    (lambda d: d.animations[-1].samplers[0].extras["cgaskin"].update(
        OUTPUT_LO=d.animations[-1].samplers[0].input),
     r"sampler 0 extras\.cgaskin\.OUTPUT_LO must be finite floats shaped like OUTPUT"),
])
def test_bad_residuals_are_refused(tmp_path, edit, message):
    path = cgaskin.save(float64_arm(), tmp_path / "arm.glb")
    with pytest.raises(ModelFormatError, match=message):
        cgaskin.load(_corrupt(path, tmp_path, edit))
