"""Errors that cannot mislead (issue 22, items 8-13): pose options that would be ignored are refused,
command-line messages name what the user typed, every public exception lives in cgaskin.errors, the
console script finds the benchmarks, --check covers every stamped file, and the smaller edges (bool
and negative indices, an overflowing translation, a complex scalpel)."""
import importlib
import inspect
import os
import pkgutil
import re
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

import cgaskin
import cgaskin.errors
from cgaskin.app import cli
from cgaskin.app.cli import main
from cgaskin.errors import InvalidInputError

REPO = Path(__file__).resolve().parents[2]
BLADE_A = ["0.6", "0.05", "1.0", "0.6", "0.05", "0.0"]
BLADE_B = ["1.2", "0.05", "1.0", "1.2", "0.05", "0.0"]


@pytest.fixture(scope="module")
def arm_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("arm") / "arm.glb"
    cgaskin.save(cgaskin.capsule_arm(), path)
    return path


def one_line_error(capsys, argv, folder):
    """Run the CLI; assert exit 2, one line on stderr, nothing written to ``folder``; the message."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cgaskin {argv[0]}: error: "), err
    assert not [p for p in folder.iterdir() if p.suffix in (".glb", ".gltf")]
    return lines[0]


# -- item 8: pose options that would be ignored ---------------------------------------------------

def _pose_argv(command, model, out, options):
    if command == "skin":
        return ["skin", model, *options, "--out", out / "o.glb"]
    if command == "cut":
        return ["cut", model, "--normal", 1, 0, 0, "--point", 1.5, 0, 0, *options, "--out", out / "a.glb",
                out / "b.glb"]
    return ["tear", model, "--from", *BLADE_A, "--to", *BLADE_B, *options, "--out", out / "t.glb"]


@pytest.mark.parametrize("command", ["skin", "cut", "tear"])
def test_a_time_without_a_clip_is_a_usage_error(arm_file, tmp_path, capsys, command):
    line = one_line_error(capsys, _pose_argv(command, arm_file, tmp_path, ["--time", "0.3"]), tmp_path)
    assert "--time 0.3" in line and "--clip" in line


@pytest.mark.parametrize("command", ["skin", "cut", "tear"])
def test_rest_and_a_clip_conflict(arm_file, tmp_path, capsys, command):
    argv = _pose_argv(command, arm_file, tmp_path, ["--rest", "--clip", "wave", "--time", "0.2"])
    line = one_line_error(capsys, argv, tmp_path)
    assert "--rest and --clip wave conflict" in line


def test_the_fox_at_a_time_without_its_clip_is_refused(models_dir, tmp_path, capsys):
    """The issue's repros on the Fox: each once wrote a pose the user did not ask for."""
    fox = models_dir / "Fox.glb"
    assert "--clip" in one_line_error(capsys, ["skin", fox, "--time", 0.3, "--out", tmp_path / "f.glb"], tmp_path)
    assert "conflict" in one_line_error(capsys, ["skin", fox, "--rest", "--clip", "Walk", "--time", 0.2,
                                                 "--out", tmp_path / "f.glb"], tmp_path)


def test_end_without_frames_is_a_usage_error(arm_file, tmp_path, capsys):
    line = one_line_error(capsys, ["skin", arm_file, "--clip", "wave", "--end", 2, "--out", tmp_path / "o.glb"],
                          tmp_path)
    assert "--end 2" in line and "--frames" in line


def test_a_clip_without_a_time_is_its_first_frame(arm_file, tmp_path, capsys):
    assert main(["skin", str(arm_file), "--clip", "wave", "--out", str(tmp_path / "o.glb")]) == 0
    rig = cgaskin.load(arm_file)
    back = cgaskin.load(tmp_path / "o.glb")      # (a posed mesh, written as a rig without a skin)
    np.testing.assert_allclose(back.vertices, cgaskin.skin(rig, rig.pose("wave", 0.0)), atol=1e-6)


# -- item 9: messages name what the user typed ----------------------------------------------------

INTERNAL = re.compile(r"save_mesh|save_gltf|scalpel_from|scalpel_to|\[Errno|\w+\(")


@pytest.mark.parametrize("options, typed", [
    (["skin", "{arm}", "--clip", "wave", "--frames", "5", "--out", "{tmp}/frames5"], "--out {tmp}/frames5"),
    (["skin", "{arm}", "--out", "{tmp}/x.obj"], "--out {tmp}/x.obj"),
    (["cut", "{arm}", "--normal", "1", "0", "0", "--point", "0", "0", "0", "--out", "{tmp}/a.obj", "{tmp}/b.glb"],
     "--out {tmp}/a.obj"),
    (["tear", "{arm}", "--from", *BLADE_A, "--to", *BLADE_B, "--out", "{tmp}/t"], "--out {tmp}/t"),
    (["skin", "{arm}", "--rotate", "elbow", "0", "0", "0", "30", "--out", "{tmp}/o.glb"], "--rotate elbow 0 0 0 30"),
    (["skin", "{arm}", "--dilate", "elbow", "0", "--out", "{tmp}/o.glb"], "--dilate elbow 0"),
    (["skin", "{arm}", "--clip", "wave", "--time", "nan", "--out", "{tmp}/o.glb"], "--time nan"),
    (["skin", "{arm}", "--clip", "wave", "--frames", "3", "--end", "inf", "--out", "{tmp}/o.glb"], "--end inf"),
    (["cut", "{arm}", "--normal", "0", "0", "0", "--point", "0", "0", "0", "--out", "{tmp}/a.glb", "{tmp}/b.glb"],
     "--normal 0 0 0"),
    (["tear", "{arm}", "--from", "1", "1", "1", "1", "1", "1", "--to", *BLADE_B, "--out", "{tmp}/t.glb"], "--from"),
    (["tear", "{arm}", "--from", *BLADE_A, "--to", "9", "9", "9", "9", "9", "8", "--out", "{tmp}/t.glb"],
     "blade at --to"),
    (["tear", "{arm}", "--from", *BLADE_A, "--to", *BLADE_B, "--opening", "-1", "--out", "{tmp}/t.glb"],
     "--opening -1"),
    (["demo", "--out", "/dev/null/demo"], "/dev/null/demo: Not a directory"),
])
def test_messages_name_the_option_as_typed(arm_file, tmp_path, capsys, options, typed):
    argv = [a.format(arm=arm_file, tmp=tmp_path) for a in options]
    line = one_line_error(capsys, argv, tmp_path)
    assert typed.format(tmp=tmp_path) in line
    assert not INTERNAL.search(line.split(": error: ", 1)[1]), line


def test_frames_into_a_name_without_an_extension(models_dir, tmp_path, capsys):
    """The issue's repro: it said "save_mesh writes .glb or .gltf"."""
    line = one_line_error(capsys, ["skin", models_dir / "Fox.glb", "--clip", "Walk", "--frames", 5,
                                   "--out", tmp_path / "frames5"], tmp_path)
    assert f"--out {tmp_path / 'frames5'}: cgaskin writes .glb or .gltf" in line
    assert "save_mesh" not in line and "frames5.glb" in line


def test_an_error_after_the_progress_bar_is_on_a_line_of_its_own(arm_file, tmp_path, capsys):
    argv = ["tear", arm_file, "--from", *BLADE_A, "--stroke", *BLADE_B, "--to", "9", "9", "9", "9", "9", "8",
            "--out", tmp_path / "t.glb"]
    assert main([str(a) for a in argv]) == 2
    last = capsys.readouterr().err.splitlines()[-1]
    assert last.startswith("cgaskin tear: error: the stroke from --stroke #1 to --to: the blade at --to")


# -- item 10: every public exception in cgaskin.errors --------------------------------------------

def test_tear_path_error_is_importable_from_errors_under_every_old_path():
    from cgaskin.errors import PlaneMissesMeshWarning, TearPathError
    from cgaskin.surgery.cut import PlaneMissesMeshWarning as from_cut
    from cgaskin.surgery.tear import TearPathError as from_tear
    from cgaskin.surgery.tear.stroke import TearPathError as from_stroke
    assert TearPathError is cgaskin.TearPathError is from_tear is from_stroke
    assert PlaneMissesMeshWarning is cgaskin.PlaneMissesMeshWarning is from_cut
    assert issubclass(TearPathError, cgaskin.errors.CgaskinError)


def test_every_exception_at_the_top_level_is_the_one_in_errors():
    exported = {name: obj for name, obj in vars(cgaskin).items()
                if inspect.isclass(obj) and issubclass(obj, BaseException)}
    assert {"TearPathError", "PlaneMissesMeshWarning", "InvalidInputError"} <= set(exported)
    for name, cls in exported.items():
        assert getattr(cgaskin.errors, name, None) is cls, name


def test_no_exception_class_is_defined_outside_errors():
    """Every runtime and rigs module (codegen is the build-time compiler, with its own CodegenError)."""
    strays = []
    for info in pkgutil.walk_packages(cgaskin.__path__, "cgaskin."):
        if info.name.startswith(("cgaskin.codegen", "cgaskin.generated")) or info.name == "cgaskin.__main__":
            continue
        module = importlib.import_module(info.name)
        strays += [f"{info.name}.{name}" for name, obj in vars(module).items()
                   if inspect.isclass(obj) and issubclass(obj, BaseException)
                   and obj.__module__.startswith("cgaskin") and obj.__module__ != "cgaskin.errors"]
    assert not strays


# -- item 11: the console script finds the benchmarks ---------------------------------------------

def _bench_help(command, cwd):
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([*command, "bench", "skinning", "--help"], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize("where", ["repository root", "elsewhere"])
def test_the_console_script_runs_the_benchmarks(tmp_path, where):
    script = shutil.which("cgaskin")
    if script is None:
        pytest.skip("the cgaskin console script is not on PATH (install the package)")
    done = _bench_help([script], REPO if where == "repository root" else tmp_path)
    assert done.returncode == 0, done.stderr
    assert "Skinning throughput" in done.stdout and "repository root" not in done.stderr


def test_python_m_cgaskin_runs_the_benchmarks_from_anywhere(tmp_path):
    done = _bench_help([sys.executable, "-m", "cgaskin"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert "Skinning throughput" in done.stdout


def test_the_benchmarks_are_found_from_the_install_or_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.benchmarks_root() == REPO                      # the editable install's tree
    wheel = tmp_path / "site-packages" / "cgaskin" / "app" / "cli.py"
    monkeypatch.setattr(cli, "__file__", str(wheel))
    assert cli.benchmarks_root() is None
    monkeypatch.chdir(REPO)
    assert cli.benchmarks_root() == REPO                      # a clone as the current folder


def test_without_the_benchmarks_it_says_what_to_do(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "__file__", str(tmp_path / "site-packages" / "cgaskin" / "app" / "cli.py"))
    assert main(["bench", "skinning"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "not installed with cgaskin" in err and "pip install -e" in err


# -- item 12: --check covers every stamped file present -------------------------------------------

@pytest.fixture
def catalogue(tmp_path):
    from tests.helpers.catalogues import README_CATALOGUE
    source = tmp_path / "mine.py"
    source.write_text(README_CATALOGUE, encoding="utf-8")
    return source


def _edit(path: Path, old: str, new: str) -> str:
    text = path.read_text(encoding="utf-8")
    assert old in text
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return text


@pytest.mark.parametrize("name, old, new", [
    ("mine.h", "mine_reflect", "mine_reflekt"),
    ("mine.wgsl", "mine_reflect", "mine_reflekt"),
    ("mine_f32.glsl", "mine_move", "mine_moove"),
    ("mine.py", "def reflect(", "def reflekt("),
])
def test_check_without_a_target_covers_every_stamped_file(catalogue, tmp_path, capsys, name, old, new):
    out = tmp_path / "gen"
    base = ["build", "--catalogue", str(catalogue), "--out", str(out)]
    assert main(base + ["--target", "numba,c,glsl,wgsl"]) == 0
    assert main(base + ["--check"]) == 0
    capsys.readouterr()
    text = _edit(out / name, old, new)                       # edited by hand
    assert main(base + ["--check"]) == 1
    assert f"stale: {out / name}" in capsys.readouterr().out
    assert main(base + ["--check", "--target", "glsl" if name != "mine_f32.glsl" else "c"]) == 1
    assert main(base) == 0                                   # a build keeps the files present fresh
    assert (out / name).read_text(encoding="utf-8") == text
    assert main(base + ["--check"]) == 0


def test_a_file_without_the_stamp_is_the_users_own(catalogue, tmp_path, capsys):
    out = tmp_path / "gen"
    base = ["build", "--catalogue", str(catalogue), "--out", str(out)]
    assert main(base) == 0
    mine = out / "mine.h"
    mine.write_text("/* my own header */\n", encoding="utf-8")
    assert main(base + ["--check"]) == 0
    assert main(base) == 0
    assert mine.read_text(encoding="utf-8") == "/* my own header */\n"


def test_the_built_in_check_covers_targets_present_beyond_the_ones_named(tmp_path):
    from cgaskin.codegen import build
    for name, text in build.render(("numba", "c", "wgsl")).items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    quiet = []
    assert build.build(check=True, directory=tmp_path, log=quiet.append, targets=("c",)) == 0
    _edit(tmp_path / "wgsl" / "cgaskin.wgsl", "fn cgaskin_", "fn cgaskin__")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append, targets=("c",)) == 1
    assert "generated/wgsl/cgaskin.wgsl" in messages[0]


# -- item 13: the smaller edges --------------------------------------------------------------------

@pytest.mark.parametrize("flag", [True, False, np.True_, np.False_])
def test_a_bool_is_not_a_clip_or_a_joint(flag):
    rig = cgaskin.capsule_arm()
    pose = rig.rest_pose()
    for call in (lambda: rig.pose(flag, 0.3), lambda: rig.poses(flag, [0.0, 0.1]), lambda: rig.clip_index(flag),
                 lambda: pose.rotate(flag, [0, 0, 1], 0.5), lambda: pose.translate(flag, [0, 1, 0]),
                 lambda: pose.dilate(flag, 2.0), lambda: rig.skeleton.node_index(flag)):
        with pytest.raises(InvalidInputError, match=r"(a bool)|unknown"):
            call()


@given(st.integers(-6, 6))
def test_one_rule_for_clip_and_joint_indices(index):
    rig = cgaskin.capsule_arm()
    bent = rig.rest_pose().rotate("elbow", [0, 0, 1], 0.4)
    rig = rig.with_clips(cgaskin.clip_from_poses("bend", [0.0, 1.0], [rig.rest_pose(), bent]))
    for count, call in ((len(rig.clips), lambda: rig.pose(index, 0.0)),
                        (rig.skeleton.n_nodes, lambda: rig.rest_pose().rotate(index, [0, 0, 1], 0.3)),
                        (rig.skeleton.n_nodes, lambda: rig.rest_pose().translate(np.int64(index), [0, 1, 0]))):
        if 0 <= index < count:
            call()
        else:
            with pytest.raises(InvalidInputError, match=rf"index {index} out of range \[0, {count}\)"):
                call()


def test_a_huge_but_finite_translation_gives_a_pose_without_warnings():
    rig = cgaskin.capsule_arm()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pose = rig.rest_pose().translate(1, [1e160, 0, 0])
        moved = rig.rest_pose().translate(1, [1e300, 0, 0]).rotate(1, [0, 0, 1], 0.5)
        skinned = cgaskin.skin(rig, pose)
    assert pose.matrices[1][0, 3] == pytest.approx(1e160, rel=1e-12)
    assert np.isfinite(moved.matrices).all() and np.isfinite(skinned).all()
    assert np.abs(skinned).max() == pytest.approx(1e160, rel=1e-6)


@pytest.mark.parametrize("edit, what", [
    (lambda p: p.translate(1, [1.7e308, 0, 0]).translate(1, [1.7e308, 0, 0]), "translate"),
    (lambda p: p.dilate(0, 1e12).dilate(0, 1e12).dilate(0, 1e12).dilate(0, 1e12), "dilate"),
])
def test_a_transform_float64_cannot_hold_is_an_error_naming_the_edit(edit, what):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InvalidInputError, match=rf"{what}\(.*overflow"):
            edit(cgaskin.capsule_arm().rest_pose())


@pytest.mark.parametrize("make", [
    lambda a: a + 0j,
    lambda a: a + 1j,
    lambda a: [list(a[0]), [a[1, 0], a[1, 1], np.complex128(a[1, 2])]],
])
def test_a_complex_scalpel_is_refused_as_the_cut_refuses_complex_input(make):
    rig = cgaskin.capsule_arm()
    a, b = np.reshape(BLADE_A, (2, 3)).astype(float), np.reshape(BLADE_B, (2, 3)).astype(float)
    with warnings.catch_warnings():
        warnings.simplefilter("error")               # no ComplexWarning: an error
        with pytest.raises(InvalidInputError, match="scalpel_from must be real, got complex values"):
            cgaskin.tear_stroke(rig, make(a), b)
        with pytest.raises(InvalidInputError, match="scalpel_to must be real, got complex values"):
            cgaskin.Surgery(rig).tear(a, make(b))
        with pytest.raises(InvalidInputError, match="normal must be real, got complex values"):
            cgaskin.cut(rig, np.array([1, 0, 0]) + 0j, [1.5, 0, 0])
