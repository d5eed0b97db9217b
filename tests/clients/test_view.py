"""`cgaskin view` and `cgaskin.show` in headless Chromium: the page opens from file:// with no request
and no console error, frames the model, plays and scrubs clips, colours weights by joint, dilates a
joint live, draws cut rims that follow the skinning, shows bone names on hover, and what it draws is
`cgaskin.skin` (three.js's skinned positions against cgaskin's, 1e-4 of the diagonal), in its default
skinning too: cgaskin's versors and generated GLSL ES, read back from the GPU against three.js's matrix
skinning read back the same way.

One browser for every page (tests/clients/js/view_page.mjs); the screenshots go to a temporary folder
(printed in the summary), or to $CGASKIN_VIEW_SCREENSHOTS when set (how docs/view/ was made)."""
import base64
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import cgaskin
from cgaskin.app.cli import main
from cgaskin.view import rim_edges
from cgaskin.view.assets import THREE_FILES, THREE_VERSION, assets_folder

from .conftest import SUMMARY

TOLERANCE = 1e-4          # of the bounding box diagonal: three.js skins in float32
BACKGROUND = np.array([0x1d, 0x20, 0x26])
WALK_TIMES = (0.2, 0.6)
HEAD, HIP, TAIL = "b_Head_05", "b_Hip_01", "b_Tail02_013"
#: the shared models (besides Fox) whose page's shader skinning is read back, each in a bent, dilated pose
SHADER_MODELS = ("Arm5.glb", "3Cylinder4bones.glb", "PlaneWith3Bones.glb", "simple_skin.gltf", "quad_skin.glb")


def _image(result) -> np.ndarray:
    rgba = np.frombuffer(base64.b64decode(result["rgba"]), np.uint8)
    return rgba.reshape(result["height"], result["width"], 4)[..., :3].astype(int)


def _covered(image) -> float:
    """The fraction of the canvas that is not background."""
    return float((np.abs(image - BACKGROUND).max(axis=2) > 12).mean())


def _changed(a, b) -> float:
    """The fraction of pixels that differ between two pictures."""
    return float((np.abs(a - b).max(axis=2) > 24).mean())


def _positions(result, n) -> np.ndarray:
    return np.frombuffer(base64.b64decode(result), "<f8").reshape(n, 3)


@pytest.fixture(scope="module")
def fox(models_dir):
    path = Path(models_dir) / "Fox.glb"
    if not path.is_file():
        pytest.skip(f"{path} is not there")
    return path, cgaskin.load(path)


@pytest.fixture(scope="module")
def arm():
    """The capsule arm cut open across the forearm (a rim), shown in a bent pose."""
    rig = cgaskin.capsule_arm()
    upper, _ = cgaskin.cut(rig, [1, 0, 0.3], [1.1, 0, 0])
    pose = upper.rest_pose().rotate("elbow", [0, 0, 1], np.radians(50)).dilate("wrist", 1.3)
    return upper, pose


def _bent(rig):
    """A pose of ``rig`` that moves it: a middle bone turned, the last one dilated."""
    bones = [rig.skeleton.names[i] for i in rig.skeleton.bone_nodes]
    return rig.rest_pose().rotate(bones[len(bones) // 2], [0.3, 1.0, 0.2], 0.6).dilate(bones[-1], 1.3)


@pytest.fixture(scope="module")
def shared(models_dir):
    """{file: (rig, its bent pose)} of SHADER_MODELS that the shared models folder holds."""
    out = {}
    for name in SHADER_MODELS:
        if (Path(models_dir) / name).is_file():
            rig = cgaskin.load(Path(models_dir) / name)
            out[name] = rig, _bent(rig)
    return out


@pytest.fixture(scope="module")
def pages(threejs, fox, arm, shared, models_dir, tmp_path_factory):
    """Every page written, opened and driven once: {"fox": record, "arm": record, ...}."""
    work = tmp_path_factory.mktemp("view")
    path, rig = fox
    start = time.perf_counter()
    fox_page = work / "fox.html"
    assert main(["view", str(path), "--clip", "Walk", "--out", str(fox_page)]) == 0   # as a user runs it
    upper, pose = arm
    notebook = work / "notebook.html"                 # what a notebook puts in its output cell
    notebook.write_text("<!doctype html><meta charset='utf-8'><body style='margin:0'>"
                        + cgaskin.show(upper, pose=pose)._repr_html_() + "</body>", encoding="utf-8")
    jobs = [
        {"name": "fox", "url": fox_page.as_uri(), "width": 720, "height": 420, "steps": [
            ["get", "clips"], ["get", "bones"], ["call", "clip"], ["call", "isPlaying"], ["call", "pause"],
            ["call", "setTime", WALK_TIMES[0]], ["call", "mixerTime"], ["pixels"], ["call", "positions"],
            ["call", "setTime", WALK_TIMES[1]], ["pixels"], ["call", "positions"], ["call", "snapshot"],
            ["dom", "#time", 0.45, "input"], ["call", "getTime"],
            ["call", "setTime", WALK_TIMES[1]],
            ["call", "setWeightJoint", TAIL], ["pixels"], ["call", "setWeightJoint", HEAD], ["pixels"],
            ["call", "showSkeleton", True], ["hoverBone", HEAD], ["call", "snapshot"],
            ["call", "showSkeleton", False], ["call", "setWeightJoint", None],
            ["call", "setDilation", HEAD, 1.8], ["pixels"], ["call", "positions"],
            ["dom", "#dilation", 1, "input"], ["pixels"],
            # 30-: cgaskin's shader against three.js's, read back from the GPU; the picture of each
            ["call", "skinning"], ["call", "shaderPositions", "cgaskin"], ["call", "shaderPositions", "three"],
            ["call", "setDilation", HEAD, 1.8], ["call", "shaderPositions", "cgaskin"],
            ["call", "setSkinning", "three"], ["pixels"], ["dom", "#skinning", "cgaskin", "change"], ["pixels"],
            ["call", "skinning"], ["value", "#clip"]]},
        {"name": "notebook", "url": notebook.as_uri(), "frame": True, "steps": [
            ["call", "clip"], ["call", "isPlaying"], ["call", "positions"], ["call", "rimCount"],
            ["call", "rimPositions"], ["call", "snapshot"],
            ["call", "setClip", "wave"], ["call", "pause"], ["call", "setTime", 0.5], ["call", "positions"],
            ["call", "shaderPositions", "cgaskin"], ["call", "shaderPositions", "three"]]},
    ]
    if "Arm5.glb" in shared:                              # a long model on a wide canvas, through its clip
        arm5 = work / "arm5.html"
        assert main(["view", str(Path(models_dir) / "Arm5.glb"), "--out", str(arm5)]) == 0
        clips = shared["Arm5.glb"][0].clips
        times = np.linspace(0, clips[0].duration, 4) if clips else [0.0]
        jobs.append({"name": "arm5", "url": arm5.as_uri(), "width": 1200, "height": 800, "steps": [
            step for t in times for step in (["call", "setTime", float(t)], ["pixels"])]})
    for name, (rig, pose) in shared.items():             # cgaskin's shader against three.js's, posed
        page = work / f"{name}.html"
        cgaskin.show(rig, pose=pose).save(page)
        jobs.append({"name": name, "url": page.as_uri(), "steps": [
            ["call", "skinning"], ["call", "shaderPositions", "cgaskin"], ["call", "shaderPositions", "three"]]})
    (work / "jobs.json").write_text(json.dumps(jobs))
    run = subprocess.run([threejs["node"], str(threejs["js"] / "view_page.mjs"), str(work / "jobs.json"),
                          str(work / "out.json")], capture_output=True, text=True, timeout=180,
                         env={**os.environ, "CGASKIN_CHROMIUM": threejs["chromium"]})
    assert run.returncode == 0, f"view_page.mjs failed:\n{run.stderr[-4000:]}"
    records = {job["name"]: record for job, record in zip(jobs, json.loads((work / "out.json").read_text()))}
    shots = Path(os.environ.get("CGASKIN_VIEW_SCREENSHOTS") or work)
    shots.mkdir(parents=True, exist_ok=True)
    for name, (job, step) in {"view_fox_walk.png": ("fox", 12), "view_fox_weights.png": ("fox", 22),
                              "view_arm_cut.png": ("notebook", 5)}.items():
        result = records[job]["results"][step] if len(records[job]["results"]) > step else None
        if isinstance(result, str) and result.startswith("data:image/png;base64,"):
            (shots / name).write_bytes(base64.b64decode(result.split(",", 1)[1]))
    SUMMARY.append(f"cgaskin view: 2 pages ({fox_page.stat().st_size / 1e6:.1f} MB Fox) driven in one Chromium "
                   f"in {time.perf_counter() - start:.1f} s; screenshots in {shots}")
    return records


@pytest.mark.parametrize("name", ["fox", "notebook"])
def test_the_page_loads_offline_without_errors(pages, name):
    record = pages[name]
    assert record["requests"] == [], f"the page made requests: {record['requests']}"
    assert record["errors"] == [], "\n".join(record["errors"])


def test_fox_is_in_frame_and_plays_what_cgaskin_skins(pages, fox):
    _, rig = fox
    r = pages["fox"]["results"]
    assert [c["name"] for c in r[0]] == [c.name for c in rig.clips]
    assert set(r[1]) == {rig.skeleton.names[i] for i in rig.skeleton.bone_nodes}
    assert r[2] == "Walk" and r[3] is True                   # --clip Walk, playing
    assert r[6] == pytest.approx(WALK_TIMES[0], abs=1e-9)    # setTime sets the mixer's time
    first, second = _image(r[7]), _image(r[10])
    for image in (first, second):
        assert 0.05 < _covered(image) < 0.9, f"the model covers {_covered(image):.1%} of the canvas"
    assert _changed(first, second) > 0.01, "two times of Walk give the same picture"
    diagonal = np.linalg.norm(np.ptp(rig.vertices, axis=0))
    for t, result in zip(WALK_TIMES, (r[8], r[11])):
        error = np.abs(_positions(result, rig.n_vertices) - cgaskin.skin(rig, rig.pose("Walk", t))).max()
        assert error / diagonal < TOLERANCE, f"Walk at {t} s: the page differs from cgaskin.skin by {error / diagonal:.2e}"


def test_the_clip_menu_shows_the_clip_that_plays(pages):
    assert pages["fox"]["results"][-1] == "Walk"           # (cgaskin view --clip Walk; Survey is the first)


def test_a_long_model_on_a_wide_canvas_is_whole_in_the_picture(pages):
    """Arm5 (its fingertips reach far from its centre) at 1200x800, at four times of its clip: no part of
    the model on the canvas's edge, and the model not lost in the middle either."""
    if "arm5" not in pages:
        pytest.skip("Arm5.glb is not in the shared models folder")
    record = pages["arm5"]
    assert record["errors"] == [], record["errors"]
    for result in record["results"][1::2]:
        model = np.abs(_image(result) - BACKGROUND).max(axis=2) > 12
        edge = np.concatenate([model[:3].ravel(), model[-3:].ravel(), model[:, :3].ravel(), model[:, -3:].ravel()])
        assert not edge.any(), f"{edge.sum()} model pixels on the canvas's edge: the picture crops the model"
        rows, columns = np.nonzero(model)
        assert max(np.ptp(rows) / model.shape[0], np.ptp(columns) / model.shape[1]) > 0.6


def test_the_scrubber_sets_the_time(pages):
    assert pages["fox"]["results"][14] == pytest.approx(0.45, abs=1e-9)


def test_weights_change_with_the_joint(pages):
    r = pages["fox"]["results"]
    plain, tail, head = _image(r[10]), _image(r[17]), _image(r[19])
    assert r[16] > 0 and r[18] > 0                     # vertices each joint influences
    assert _changed(plain, head) > 0.02 and _changed(head, tail) > 0.02


def test_bone_names_on_hover(pages):
    assert pages["fox"]["results"][21] == HEAD


def test_dilation_is_the_algebras(pages, fox):
    _, rig = fox
    r = pages["fox"]["results"]
    plain, dilated, undone = _image(r[10]), _image(r[26]), _image(r[29])
    assert _changed(plain, dilated) > 0.005
    assert _changed(plain, undone) < 0.001               # the slider back at 1: the clip's pose again
    expected = cgaskin.skin(rig, rig.pose("Walk", WALK_TIMES[1]).dilate(HEAD, 1.8))
    error = np.abs(_positions(r[27], rig.n_vertices) - expected).max() / np.linalg.norm(np.ptp(rig.vertices, axis=0))
    assert error < TOLERANCE, f"dilating {HEAD} by 1.8: the page differs from Pose.dilate by {error:.2e}"


def test_cgaskin_shader_skins_as_threejs_and_cgaskin_do(pages, fox, arm):
    """The page's default skinning is cgaskin's: the bones' versors composed by the generated JavaScript
    kernels, blended by the generated GLSL ES in the vertex shader. Read back from the GPU (a float
    render target), it equals three.js's matrix skinning read back the same way, and cgaskin.skin, to
    1e-4 of the diagonal (float32 on the GPU), also with a dilated joint and on a cut rig; switching
    the mode from the page's control leaves the picture as it was."""
    _, rig = fox
    r = pages["fox"]["results"]
    diagonal = np.linalg.norm(np.ptp(rig.vertices, axis=0))
    assert r[30] == "cgaskin" and r[39] == "cgaskin"
    ours, theirs = _positions(r[31], rig.n_vertices), _positions(r[32], rig.n_vertices)
    SUMMARY.append(f"cgaskin view: cgaskin's shader skinning against three.js's on the GPU (Fox, Walk): "
                   f"{np.abs(ours - theirs).max() / diagonal:.1e} of the diagonal")
    assert np.abs(ours - theirs).max() / diagonal < TOLERANCE
    assert np.abs(ours - cgaskin.skin(rig, rig.pose("Walk", WALK_TIMES[1]))).max() / diagonal < TOLERANCE
    dilated = cgaskin.skin(rig, rig.pose("Walk", WALK_TIMES[1]).dilate(HEAD, 1.8))
    assert np.abs(_positions(r[34], rig.n_vertices) - dilated).max() / diagonal < TOLERANCE
    assert np.abs(dilated - theirs).max() / diagonal > 10 * TOLERANCE       # (the dilation moved the head)
    assert _changed(_image(r[36]), _image(r[38])) < 0.002
    upper, _ = arm
    n = pages["notebook"]["results"]
    arm_diagonal = np.linalg.norm(np.ptp(upper.vertices, axis=0))
    ours, theirs = _positions(n[10], upper.n_vertices), _positions(n[11], upper.n_vertices)
    assert np.abs(ours - theirs).max() / arm_diagonal < TOLERANCE
    assert np.abs(ours - cgaskin.skin(upper, upper.pose("wave", 0.5))).max() / arm_diagonal < TOLERANCE


@pytest.mark.parametrize("name", SHADER_MODELS)
def test_cgaskin_shader_skins_the_shared_models_as_threejs_does(pages, shared, name):
    """On every shared glTF model, bent and dilated (``_bent``): cgaskin's shader skinning read back from
    the GPU equals three.js's read back the same way and cgaskin.skin, 1e-4 of the diagonal."""
    if name not in shared:
        pytest.skip(f"{name} is not in the shared models folder")
    rig, pose = shared[name]
    record = pages[name]
    assert record["errors"] == [] and record["requests"] == [], record
    r = record["results"]
    assert r[0] == "cgaskin"
    ours, theirs = _positions(r[1], rig.n_vertices), _positions(r[2], rig.n_vertices)
    expected = cgaskin.skin(rig, pose)
    diagonal = np.linalg.norm(np.ptp(expected, axis=0))
    assert np.abs(ours - theirs).max() / diagonal < TOLERANCE
    assert np.abs(ours - expected).max() / diagonal < TOLERANCE
    assert np.abs(expected - cgaskin.skin(rig, rig.rest_pose())).max() / diagonal > 10 * TOLERANCE   # (it moved)


def test_show_in_a_notebook_iframe_shows_the_pose_and_the_rims(pages, arm):
    upper, pose = arm
    r = pages["notebook"]["results"]
    diagonal = np.linalg.norm(np.ptp(upper.vertices, axis=0))
    assert r[0] == "pose" and r[1] is False              # the pose, held still
    shown = _positions(r[2], upper.n_vertices)
    assert np.abs(shown - cgaskin.skin(upper, pose)).max() / diagonal < TOLERANCE
    rims = rim_edges(upper)
    assert len(rims) > 0 and r[3] == len(rims)
    lines = np.frombuffer(base64.b64decode(r[4]), "<f8").reshape(-1, 3)
    assert np.abs(lines - shown[rims.reshape(-1)]).max() / diagonal < TOLERANCE   # the rims follow the skin
    waved = _positions(r[9], upper.n_vertices)
    assert np.abs(waved - cgaskin.skin(upper, upper.pose("wave", 0.5))).max() / diagonal < TOLERANCE


def test_rims_are_the_open_edges():
    rig = cgaskin.capsule_arm()
    assert len(rim_edges(rig)) == 0                      # a closed capsule
    upper, _ = cgaskin.cut(rig, [1, 0, 0], [1.1, 0, 0])
    rims = rim_edges(upper)
    assert np.allclose(upper.vertices[rims.reshape(-1), 0], 1.1)   # all on the cut plane
    capped, _ = cgaskin.cut(rig, [1, 0, 0], [1.1, 0, 0], cap=True)
    assert len(rim_edges(capped)) == 0


def test_view_refuses_an_unknown_clip_naming_the_clips(fox, tmp_path, capsys):
    path, _ = fox
    assert main(["view", str(path), "--clip", "Jump", "--out", str(tmp_path / "x.html")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("cgaskin view: error:") and "'Survey', 'Walk', 'Run'" in err
    assert main(["view", str(path), "--out", str(tmp_path / "x.glb")]) == 2
    assert not (tmp_path / "x.html").exists()
    with pytest.raises(cgaskin.InvalidInputError, match="not both"):
        cgaskin.show(cgaskin.capsule_arm(), pose=cgaskin.capsule_arm().rest_pose(), clip="wave")


def test_import_cgaskin_does_not_load_the_viewer():
    code = "import sys, cgaskin; print('cgaskin.view' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "False"


def test_vendored_threejs_is_the_pinned_npm_version(threejs):
    package = threejs["js"] / "node_modules" / "three"
    pinned = json.loads((threejs["js"] / "package.json").read_text())["dependencies"]["three"]
    assert THREE_VERSION == pinned == json.loads((package / "package.json").read_text())["version"]
    different = [mine for mine, theirs in THREE_FILES.items()
                 if (assets_folder() / "three" / mine).read_bytes() != (package / theirs).read_bytes()]
    assert different == [], f"vendored three.js differs from npm three {pinned}: run scripts/vendor-three.sh"


@pytest.mark.parametrize("time", ["x", None, True, float("nan"), -1.0])
def test_a_time_that_is_not_seconds_is_refused_by_name(time):
    with pytest.raises(cgaskin.errors.InvalidInputError, match="time"):
        cgaskin.view.view_html(cgaskin.capsule_arm(), time=time)


def test_a_module_the_page_does_not_inline_is_cgaskins_bug(monkeypatch):
    """A three.js file importing a file the page does not carry (a vendored update that added one)."""
    from cgaskin.view import page
    monkeypatch.setattr(page, "MODULES", {k: v for k, v in page.MODULES.items() if k != "three/three.core.js"})
    with pytest.raises(cgaskin.errors.InternalError, match="does not inline"):
        page.module_text("three")
