"""The batch spec and its items, without a cluster: errors name the key, ids are content hashes."""
import subprocess
import sys
from pathlib import Path

import pytest

from cgaskin.app.cli import main
from cgaskin.batch import expand, load_spec, parse_spec
from cgaskin.errors import InvalidInputError


def _spec(tmp_path, text: str):
    path = tmp_path / "spec.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def fox(models_dir):
    return str(models_dir / "Fox.glb")


BASE = '''seed = 3
[[models]]
path = "{fox}"
[[poses]]
clip = "Walk"
times = [0.0, 0.25]
[[operations]]
kind = "cut"
[[operations]]
kind = "drill"
radius = 0.02
'''


@pytest.mark.parametrize("change, key", [
    (("seed = 3", "seed = -1"), "seed"),
    (("seed = 3", "sed = 3"), "sed"),
    (('kind = "drill"', 'kind = "slice"'), "operations[1].kind"),
    (('kind = "cut"', 'kind = "cut"\ncount = 0'), "operations[0].count"),
    (('kind = "cut"', 'kind = "cut"\nradius = 0.1'), "operations[0].radius"),
    (("radius = 0.02", "radius = [0.2, 0.1]"), "operations[1].radius"),
    (("radius = 0.02", "radius = -1"), "operations[1].radius"),
    (("times = [0.0, 0.25]", "times = []"), "poses[0].times"),
    (("times = [0.0, 0.25]", "times = [0.0]\nrest = true"), "poses[0]"),
    (("times = [0.0, 0.25]", "times = [0.0]\nedits = { dilate = { joint = 2, range = [-1, 2] } }"),
     "poses[0].edits.dilate.range"),
    (("times = [0.0, 0.25]", "times = [0.0]\nedits = { scale = { joint = 2, range = 1 } }"), "poses[0].edits.scale"),
    (("times = [0.0, 0.25]", "times = [0.0]\nedits = { rotate = { range = 10 } }"), "poses[0].edits.rotate.joint"),
    (('path = "{fox}"', 'path = "nothing/*.glb"'), "models[0].path"),
    (('path = "{fox}"', 'path = "absent.glb"'), "models[0].path"),
    (('path = "{fox}"', 'file = "{fox}"'), "models[0].file"),
])
def test_a_spec_error_names_the_key(tmp_path, fox, change, key):
    text = BASE.replace(*change).replace("{fox}", fox)
    with pytest.raises(InvalidInputError) as err:
        load_spec(_spec(tmp_path, text))
    assert f"spec.toml: {key}: " in str(err.value)


def test_toml_syntax_and_missing_models_are_errors(tmp_path):
    with pytest.raises(InvalidInputError, match="not valid TOML"):
        load_spec(_spec(tmp_path, "seed = = 3"))
    with pytest.raises(InvalidInputError, match=r"models: missing"):
        load_spec(_spec(tmp_path, "seed = 3"))


def test_defaults_globs_and_names(tmp_path, models_dir):
    (tmp_path / "models").mkdir()
    for name in ("Fox.glb", "Arm5.glb"):         # (links: the models stay in the shared folder)
        (tmp_path / "models" / name).symlink_to(models_dir / name)
    spec = load_spec(_spec(tmp_path, '[[models]]\npath = "models/*.glb"\n[[models]]\npath = "models/Fox.glb"\n'))
    assert [m.name for m in spec.models] == ["models/Arm5.glb", "models/Fox.glb"]    # sorted, once each
    assert spec.seed == 0 and spec.poses[0].clip is None and spec.operations[0].kind == "none"
    drill = parse_spec({"models": [{"path": "models/Fox.glb"}], "operations": [{"kind": "drill"}]}, tmp_path)
    assert dict(drill.operations[0].params) == {"radius": (0.03, 0.03), "depth": (0.15, 0.15), "wall": True}


def test_ids_are_content_hashes(tmp_path, fox, models_dir):
    items = expand(load_spec(_spec(tmp_path, BASE.replace("{fox}", fox))))
    assert len(items) == 4 and len({i.id for i in items}) == 4
    # the same file through another path: the same ids
    (tmp_path / "elsewhere.glb").symlink_to(models_dir / "Fox.glb")
    moved = expand(load_spec(_spec(tmp_path, BASE.replace("{fox}", "elsewhere.glb"))))
    assert [i.id for i in moved] == [i.id for i in items]
    # a changed drill changes the drill items only; one more instance keeps the first
    changed = expand(load_spec(_spec(tmp_path, BASE.replace("radius = 0.02", "radius = 0.025\ncount = 2")
                                     .replace("{fox}", fox))))
    same = {i.id for i in changed} & {i.id for i in items}
    assert same == {i.id for i in items if i.operation == "cut"}
    assert len(changed) == 6
    # another seed: every id changes, and so do the draws
    reseeded = expand(load_spec(_spec(tmp_path, BASE.replace("seed = 3", "seed = 4").replace("{fox}", fox))))
    assert not {i.id for i in reseeded} & {i.id for i in items}
    assert items[0].rng().random() == items[0].rng().random() != reseeded[0].rng().random()


def test_the_cli_exits_2_naming_the_key(tmp_path, fox, capsys):
    path = _spec(tmp_path, BASE.replace('kind = "drill"', 'kind = "slice"').replace("{fox}", fox))
    assert main(["batch", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "cgaskin batch: error:" in err and "operations[1].kind" in err and "'slice'" in err
    assert not (tmp_path / "out").exists()
    assert main(["batch", str(path), "--out", str(tmp_path / "out"), "--workers", "0"]) == 2
    assert "--workers 0" in capsys.readouterr().err


def test_importing_cgaskin_imports_no_dask():
    code = ("import sys, cgaskin, cgaskin.batch, cgaskin.app.cli; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed', 'pyarrow')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_the_batch_pages_spec_is_valid(tmp_path, models_dir):
    import textwrap
    page = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "batch.rst").read_text(encoding="utf-8")
    text = textwrap.dedent(page.split(".. code-block:: toml\n\n")[1].split("\n\n")[0])
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "Fox.glb").symlink_to(models_dir / "Fox.glb")
    spec = load_spec(_spec(tmp_path, text))
    assert [e.kind for e in spec.poses[0].edits] == ["dilate", "rotate"]
    assert dict(spec.operations[0].params)["radius"] == (0.02, 0.04)
    assert len(expand(spec)) == 1 * 3 * 3


# -- issue 43 D14: the data a batch keeps ------------------------------------------------------------

def test_a_folder_as_a_model_path_is_named_a_folder(tmp_path, fox):
    (tmp_path / "models").mkdir()
    with pytest.raises(InvalidInputError) as err:
        load_spec(_spec(tmp_path, BASE.replace(fox, "models").replace("{fox}", "models")))
    assert "models[0].path" in str(err.value) and "is a directory" in str(err.value)
    assert "no such file" not in str(err.value)


def test_each_unreadable_model_keeps_its_items(tmp_path):
    """Two models that cannot be read (gone after the spec was read) once hashed alike: the second's
    items were dropped as duplicates of the first's, without a row."""
    import cgaskin
    for name in ("a.glb", "b.glb"):
        cgaskin.save(cgaskin.capsule_arm(), tmp_path / name)
    spec = load_spec(_spec(tmp_path, '[[models]]\npath = "a.glb"\n[[models]]\npath = "b.glb"\n'
                                     '[[operations]]\nkind = "cut"\ncount = 2\n'))
    for name in ("a.glb", "b.glb"):
        (tmp_path / name).unlink()
    items = expand(spec)
    assert [i.model for i in items] == ["a.glb", "a.glb", "b.glb", "b.glb"]
    assert len({i.id for i in items}) == 4 and all(i.model_sha256.startswith("unreadable:") for i in items)


def test_the_item_ids_change_with_cgaskin_s_version(tmp_path, fox, monkeypatch):
    """A resume after an upgrade (another algorithm) makes every item again, never keeps old outputs."""
    import cgaskin
    from cgaskin._shared import version
    assert cgaskin.__version__ == version.VERSION
    spec = load_spec(_spec(tmp_path, BASE.replace("{fox}", fox)))
    before = [i.id for i in expand(spec)]
    monkeypatch.setattr(version, "VERSION", version.VERSION + ".post1")
    after = [i.id for i in expand(spec)]
    assert len(after) == len(before) and not set(after) & set(before)
