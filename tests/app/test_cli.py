"""The command line, in process: the demo, skin, cut and tear on real files, and its errors."""
import numpy as np
import pytest

import cgaskin
from cgaskin import capsule_arm
from cgaskin.app.cli import main


def read_mesh(path):
    """(positions, faces) of the single mesh of a file written by ``save_mesh``."""
    from tests.helpers.gltf_reference import _File
    f = _File(path)
    prim = f.gltf.meshes[0].primitives[0]
    return f.accessor(prim.attributes.POSITION), f.accessor(prim.indices).reshape(-1, 3), f, prim


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def test_demo_writes_pictures_and_rigs(tmp_path, capsys):
    code, out, err = run(capsys, "demo", "--out", tmp_path)
    assert code == 0 and err == ""
    for name in ("deform.png", "cut.png", "tear.png", "drill.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    arm = cgaskin.load(tmp_path / "capsule_arm.glb")
    drilled = cgaskin.load(tmp_path / "drilled.glb")
    assert drilled.n_faces > arm.n_faces and drilled.clips[0].name == "wave"
    upper, lower = cgaskin.load(tmp_path / "cut_upper.glb"), cgaskin.load(tmp_path / "cut_lower.glb")
    torn = cgaskin.load(tmp_path / "torn.glb")
    assert arm.n_vertices == capsule_arm().n_vertices
    assert upper.n_faces > 0 and lower.n_faces > 0 and upper.n_faces + lower.n_faces > arm.n_faces
    assert torn.n_vertices > arm.n_vertices and torn.clips[0].name == "wave"


def test_skin_at_a_clip_time_with_edits(models_dir, tmp_path, capsys):
    path = models_dir / "Fox.glb"
    code, out, _ = run(capsys, "skin", path, "--clip", "Walk", "--time", 0.4, "--rotate", "b_Neck_04",
                       0, 0, 1, 30, "--dilate", "b_Tail01_012", 1.5, "--translate", 3, 0, 5, 0,
                       "--out", tmp_path / "fox.glb")
    assert code == 0 and "fox.glb" in out
    rig = cgaskin.load(path)
    pose = (rig.pose("Walk", 0.4).rotate("b_Neck_04", [0, 0, 1], np.radians(30))
            .dilate("b_Tail01_012", 1.5).translate(3, [0, 5, 0]))
    positions, faces, f, prim = read_mesh(tmp_path / "fox.glb")
    expected = cgaskin.skin(rig, pose)
    np.testing.assert_allclose(positions, expected, rtol=1e-6, atol=1e-6 * np.ptp(expected, axis=0).max())
    np.testing.assert_array_equal(faces, rig.faces)
    assert prim.attributes.NORMAL is None                    # the Fox has no normals to skin


def test_skin_writes_skinned_normals(models_dir, tmp_path, capsys):
    rig = cgaskin.load(models_dir / "Arm5.glb")
    joint = rig.skeleton.names[5]
    code, _, _ = run(capsys, "skin", models_dir / "Arm5.glb", "--rotate", joint, 1, 0, 0, 40, "--dilate",
                     joint, 0.7, "--out", tmp_path / "arm.gltf")
    assert code == 0
    pose = rig.rest_pose().rotate(joint, [1, 0, 0], np.radians(40)).dilate(joint, 0.7)
    positions, _, f, prim = read_mesh(tmp_path / "arm.gltf")
    np.testing.assert_allclose(positions, cgaskin.skin(rig, pose), atol=1e-5)
    np.testing.assert_allclose(f.accessor(prim.attributes.NORMAL), cgaskin.skin_normals(rig, pose), atol=1e-6)
    assert not np.allclose(cgaskin.skin_normals(rig, pose), rig.attributes["NORMAL"], atol=1e-2)


def test_skin_bakes_frames(models_dir, tmp_path, capsys):
    code, out, err = run(capsys, "skin", models_dir / "simple_skin.gltf", "--clip", 0, "--frames", 3,
                         "--out", tmp_path / "s.glb")
    assert code == 0 and "skinning" in err                 # the progress bar
    rig = cgaskin.load(models_dir / "simple_skin.gltf")
    for i, t in enumerate(np.linspace(0, rig.clips[0].duration, 3)):
        positions, _, _, _ = read_mesh(tmp_path / f"s_{i:04d}.glb")
        np.testing.assert_allclose(positions, cgaskin.skin(rig, rig.pose(0, t)), atol=1e-6)


def test_cut_writes_both_halves(models_dir, tmp_path, capsys):
    path = models_dir / "Arm5.glb"
    rig = cgaskin.load(path)
    pose = rig.rest_pose().rotate(rig.skeleton.names[3], [0, 0, 1], np.radians(20))
    centre = cgaskin.skin(rig, pose).mean(axis=0)
    code, out, _ = run(capsys, "cut", path, "--normal", 1, 0.2, 0, "--point", *centre, "--cap",
                       "--rotate", rig.skeleton.names[3], 0, 0, 1, 20,
                       "--out", tmp_path / "a.glb", tmp_path / "b.glb")
    assert code == 0
    expected = cgaskin.cut(rig, [1, 0.2, 0], centre, pose=pose, cap=True)
    for half, name in zip(expected, ("a.glb", "b.glb")):
        back = cgaskin.load(tmp_path / name)
        np.testing.assert_array_equal(back.faces, half.faces)
        np.testing.assert_allclose(back.vertices, half.vertices, atol=1e-6)


def test_cut_of_the_rest_pose_where_it_is_not_the_stored_mesh(models_dir, tmp_path, capsys):
    """3Cylinder4bones stores its mesh away from where its rest pose puts it (bind matrices that are
    not the rest pose's): --rest cuts what a viewer shows, the default the mesh as stored."""
    path = models_dir / "3Cylinder4bones.glb"
    rig = cgaskin.load(path)
    shown = cgaskin.skin(rig)
    size = np.ptp(shown, axis=0).max()
    axis = int(np.argmax(np.abs(shown - rig.vertices).mean(axis=0)))    # where they differ most
    assert np.abs(shown - rig.vertices)[:, axis].mean() > 0.1 * size
    normal = np.eye(3)[axis]
    centre = shown.mean(axis=0)
    code, _, _ = run(capsys, "cut", path, "--rest", "--normal", *normal, "--point", *centre,
                     "--out", tmp_path / "a.glb", tmp_path / "b.glb")
    assert code == 0
    expected = cgaskin.cut(rig, normal, centre, pose=rig.rest_pose())
    for half, name in zip(expected, ("a.glb", "b.glb")):
        back = cgaskin.load(tmp_path / name)
        np.testing.assert_array_equal(back.faces, half.faces)
        # the vertices the cut made lie on the plane where a viewer shows them, not where stored
        stored = {tuple(v) for v in rig.vertices}
        new = np.array([i for i, v in enumerate(back.vertices) if tuple(v) not in stored])
        assert len(new) > 0
        assert np.abs(cgaskin.skin(back)[new, axis] - centre[axis]).max() <= 1e-5 * size
        assert np.abs(back.vertices[new, axis] - centre[axis]).min() > 1e-2 * size


def test_cut_that_misses_writes_one_half(models_dir, tmp_path, capsys):
    code, out, err = run(capsys, "cut", models_dir / "Arm5.glb", "--normal", 1, 0, 0, "--point", 1e3, 0, 0,
                         "--out", tmp_path / "a.glb", tmp_path / "b.glb")
    assert code == 0 and "does not cross the mesh" in err and "empty; not written" in out
    assert not (tmp_path / "a.glb").exists() and (tmp_path / "b.glb").exists()


def test_tear_of_a_saved_arm(tmp_path, capsys):
    rig = capsule_arm()
    cgaskin.save(rig, tmp_path / "arm.glb")
    blades = ([0.6, 0.05, 1.0, 0.6, 0.05, 0.0], [1.2, 0.05, 1.0, 1.2, 0.05, 0.0])
    code, out, _ = run(capsys, "tear", tmp_path / "arm.glb", "--from", *blades[0], "--to", *blades[1],
                       "--opening", 0.05, "--out", tmp_path / "torn.glb")
    assert code == 0
    expected = cgaskin.tear(cgaskin.load(tmp_path / "arm.glb"), np.reshape(blades[0], (2, 3)),
                            np.reshape(blades[1], (2, 3)), opening=0.05)
    back = cgaskin.load(tmp_path / "torn.glb")
    np.testing.assert_array_equal(back.faces, expected.faces)
    assert back.n_vertices == expected.n_vertices > rig.n_vertices


@pytest.mark.parametrize("argv, message", [
    (["skin", "{models}/nope.glb", "--out", "{tmp}/x.glb"], "no such file"),
    (["skin", "{models}/Fox.glb", "--clip", "Fly", "--out", "{tmp}/x.glb"], "unknown clip 'Fly'; valid clips: 'Survey'"),
    (["skin", "{models}/Fox.glb", "--dilate", "tail", "2", "--out", "{tmp}/x.glb"], "unknown joint 'tail'"),
    (["skin", "{models}/Arm5.glb", "--frames", "4", "--out", "{tmp}/x.glb"], "name it with --clip"),
    (["skin", "{models}/Fox.glb", "--out", "{tmp}/x.obj"], "writes .glb or .gltf"),
    (["cut", "{models}/Arm5.glb", "--normal", "0", "0", "0", "--point", "0", "0", "0",
      "--out", "{tmp}/a.glb", "{tmp}/b.glb"], "normal"),
    (["tear", "{models}/Arm5.glb", "--from", "9", "9", "9", "9", "9", "8", "--to", "9", "8", "9", "9", "8", "8",
      "--out", "{tmp}/t.glb"], "does not meet the surface"),
])
def test_errors_are_messages_not_tracebacks(models_dir, tmp_path, capsys, argv, message):
    argv = [a.format(models=models_dir, tmp=tmp_path) for a in argv]
    code, _, err = run(capsys, *argv)
    last = err.splitlines()[-1]            # after any warnings the model's loading gave
    assert code == 2 and last.startswith(f"cgaskin {argv[0]}: error: ") and message in last
    assert not list(tmp_path.iterdir())                     # nothing half-written


def test_tear_takes_a_sequence_of_blade_positions(models_dir, tmp_path, capsys):
    """Issue 10, item 1: one progressive tear from the command line, by --stroke or a file, equal to
    the strokes made one after another from Python."""
    model = models_dir / "Fox.glb"
    blades = [[0.3, 120, 0.7, 0.3, 40, 0.7], [0.3, 120, 10.1, 0.3, 40, 10.1], [0.3, 120, 20.3, 0.3, 40, 20.3]]
    expected = cgaskin.load(model)
    for a, b in zip(blades[:-1], blades[1:]):
        expected = cgaskin.tear(expected, np.reshape(a, (2, 3)), np.reshape(b, (2, 3)))
    by_options = ["--stroke", *map(str, blades[0]), "--stroke", *map(str, blades[1]),
                  "--stroke", *map(str, blades[2])]
    listing = tmp_path / "blades.txt"
    listing.write_text("# handle, tip\n" + "\n".join(", ".join(map(str, b)) for b in blades) + "\n")
    for i, options in enumerate((by_options, ["--strokes", str(listing)],
                                 ["--from", *map(str, blades[0]), "--stroke", *map(str, blades[1]),
                                  "--to", *map(str, blades[2])])):
        out = tmp_path / f"torn{i}.glb"
        assert main(["tear", str(model), *options, "--out", str(out)]) == 0
        torn = cgaskin.load(out)
        np.testing.assert_array_equal(torn.faces, expected.faces)
        np.testing.assert_array_equal(torn.vertices, expected.vertices)
    assert "2 stroke(s)" in capsys.readouterr().out


def test_tear_needs_two_blade_positions(models_dir, tmp_path, capsys):
    model = str(models_dir / "Fox.glb")
    assert main(["tear", model, "--stroke", *["1"] * 6, "--out", str(tmp_path / "t.glb")]) == 2
    assert "two times at least" in capsys.readouterr().err
    bad = tmp_path / "bad.txt"
    bad.write_text("1 2 3 4 5\n")
    assert main(["tear", model, "--strokes", str(bad), "--out", str(tmp_path / "t.glb")]) == 2
    assert "line 1: give 6 numbers" in capsys.readouterr().err
