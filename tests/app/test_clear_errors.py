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
