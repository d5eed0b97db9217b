"""Mistakes a user makes get a specific error and lose nothing (issue 10, "clear errors")."""
import warnings

import numpy as np
import pytest

import cgaskin
from cgaskin.app.cli import main
from cgaskin.errors import InvalidInputError, ModelFormatError


def test_load_and_save_refuse_what_is_not_a_path_or_a_rig(tmp_path):
    with pytest.raises(InvalidInputError, match="path must be a file path"):
        cgaskin.load(None)
    with pytest.raises(InvalidInputError, match="rig must be a cgaskin.Rig"):
        cgaskin.save("rig", tmp_path / "a.glb")
    with pytest.raises(InvalidInputError, match="path must be a file path"):
        cgaskin.save(cgaskin.capsule_arm(), 3)


@pytest.mark.parametrize("name", ["model.fbx", "model.glb"])
def test_a_directory_is_not_a_model(tmp_path, name):
    (tmp_path / name).mkdir()
    with pytest.raises(ModelFormatError, match="is a directory"):
        cgaskin.load(tmp_path / name)


def test_a_mesh_in_the_cutting_plane_is_reported_as_such():
    arm = cgaskin.capsule_arm()
    square = cgaskin.Rig(vertices=np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
                         faces=np.array([[0, 1, 2], [0, 2, 3]]), joints=np.zeros((4, 4), np.int64),
                         weights=np.tile([1.0, 0, 0, 0], (4, 1)), skeleton=arm.skeleton, name="square")
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        positive, negative = cgaskin.cut(square, [0, 0, 1.0], [0, 0, 0])
    messages = [str(w.message) for w in record if w.category is cgaskin.PlaneMissesMeshWarning]
    # the faces face +z: they bound what lies below them, the negative half
    assert negative.n_faces == 2 and positive.n_faces == 0
    assert len(messages) == 1 and "lies in the plane" in messages[0] and "negative half" in messages[0]


def test_frames_must_be_at_least_one(tmp_path, capsys):
    path = tmp_path / "arm.glb"
    cgaskin.save(cgaskin.capsule_arm(), path)
    assert main(["skin", str(path), "--clip", "wave", "--frames", "0", "--out", str(tmp_path / "o.glb")]) == 2
    assert "--frames must be at least 1" in capsys.readouterr().err
    assert not (tmp_path / "o.glb").exists()


def test_cut_refuses_one_output_file_for_both_halves(tmp_path, capsys):
    path = tmp_path / "arm.glb"
    cgaskin.save(cgaskin.capsule_arm(), path)
    same = str(tmp_path / "half.glb")
    code = main(["cut", str(path), "--normal", "1", "0", "0", "--point", "1.5", "0", "0", "--out", same, same])
    assert code == 2 and "names one file twice" in capsys.readouterr().err
    assert not (tmp_path / "half.glb").exists()


def test_skin_help_names_its_default_pose(capsys):
    with pytest.raises(SystemExit):
        main(["skin", "--help"])
    text = capsys.readouterr().out
    assert "default: the rest pose" in text and "the mesh as stored" not in text
    with pytest.raises(SystemExit):
        main(["cut", "--help"])
    assert "default: the mesh as stored" in capsys.readouterr().out


# -- issue 43 D16: every error and warning a cgaskin class that says what to do ------------------------

def test_loader_and_rig_warnings_are_cgaskin_s_model_warning(models_dir, tmp_path):
    assert cgaskin.ModelWarning is cgaskin.errors.ModelWarning and issubclass(cgaskin.ModelWarning, UserWarning)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        cgaskin.load(models_dir / "Arm5.glb")                       # weights that do not sum to 1
        arm = cgaskin.capsule_arm()
        cgaskin.Rig(vertices=arm.vertices, faces=arm.faces, joints=arm.joints, weights=arm.weights * 1.01,
                    skeleton=arm.skeleton, name="heavy")
    assert len(record) == 2 and all(w.category is cgaskin.ModelWarning for w in record), \
        [(w.category, str(w.message)) for w in record]
    silent = cgaskin.Clip("silent", ())                             # glTF animations need a channel
    with pytest.warns(cgaskin.ModelWarning, match="no channels"):
        cgaskin.save(arm.with_clips(silent), tmp_path / "silent.glb")


def test_an_unreadable_manifest_is_a_cgaskin_warning(tmp_path):
    from cgaskin.batch import read_manifest
    (tmp_path / "manifest.parquet").write_bytes(b"PAR1 not parquet")
    with pytest.warns(cgaskin.errors.ManifestWarning, match="every item is made again"):
        assert read_manifest(tmp_path / "manifest.parquet") == []


def test_saving_into_a_missing_folder_names_the_folder(tmp_path, capsys):
    from cgaskin.errors import MissingFolderError
    from cgaskin.rigs.export import save_mesh
    arm = cgaskin.capsule_arm()
    missing = tmp_path / "frames"
    for write in (lambda: cgaskin.save(arm, missing / "a.glb"),
                  lambda: save_mesh(arm.vertices, arm.faces, missing / "a.gltf")):
        with pytest.raises(MissingFolderError, match=f"{missing}: no such folder") as err:
            write()
        assert isinstance(err.value, FileNotFoundError) and "make it first" in str(err.value)
    path = tmp_path / "arm.glb"
    cgaskin.save(arm, path)
    assert main(["skin", str(path), "--out", str(missing / "o.glb")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and f"{missing}: no such folder" in lines[0]
    assert not missing.exists()


@pytest.mark.parametrize("radius", ["0", "-0.5"])
def test_drill_names_its_radius(tmp_path, capsys, radius):
    path = tmp_path / "arm.glb"
    cgaskin.save(cgaskin.capsule_arm(), path)
    code = main(["drill", str(path), "--start", "0.5", "0", "-1", "--end", "0.5", "0", "1", "--radius", radius,
                 "--out", str(tmp_path / "d.glb")])
    err = capsys.readouterr().err
    assert code == 2 and f"--radius {radius}" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "d.glb").exists()


def test_the_formats_page_names_the_tear_attribute_as_files_hold_it():
    from pathlib import Path
    from cgaskin.surgery.tear import TEAR_LABEL
    readme = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "formats.rst").read_text(encoding="utf-8")
    torn = cgaskin.tear(cgaskin.capsule_arm(), ([0.6, 0.05, 1.0], [0.6, 0.05, 0.0]),
                        ([1.2, 0.05, 1.0], [1.2, 0.05, 0.0]))
    assert TEAR_LABEL in torn.attributes and f"``{TEAR_LABEL}``" in readme
    assert "TEAR_LABEL" not in readme.replace("cgaskin.surgery.tear.TEAR_LABEL", "")
