"""`cgaskin build --target`: every printer's files written, checked for staleness (sympy version aside)
and refused with a clear error for an unknown target, for the built-in catalogue and a user's."""
import pytest

from cgaskin.app.cli import main as cli_main
from cgaskin.codegen import build
from cgaskin.codegen.targets import TARGETS

from tests.helpers.catalogues import PGA_CATALOGUE, README_CATALOGUE

EXPECTED = {"c": {"{p}.h", "{p}_f32.h"}, "glsl": {"{p}.glsl", "{p}_f32.glsl"}, "wgsl": {"{p}.wgsl"},
            "cuda": {"{p}_cuda.py", "{p}.cuh"}}


def test_a_user_catalogue_builds_for_every_target_and_check_names_a_stale_file(tmp_path, capsys):
    source = tmp_path / "mine.py"
    pga_kernels = PGA_CATALOGUE.replace("def move(", "def pga_move(").replace("def reflect(", "def pga_reflect(")
    source.write_text(README_CATALOGUE + pga_kernels, encoding="utf-8")     # CGA and PGA kernels in one file
    out = tmp_path / "out"
    args = ["build", "--catalogue", str(source), "--out", str(out), "--target", ",".join(TARGETS)]
    assert cli_main(args) == 0
    written = {p.name for p in out.iterdir() if p.is_file()}
    want = {"mine.py"} | {name.format(p="mine") for names in EXPECTED.values() for name in names}
    assert want <= written
    assert "pga_move" in (out / "mine.h").read_text() and "mine_move" in (out / "mine.wgsl").read_text()
    capsys.readouterr()
    assert cli_main(args + ["--check"]) == 0

    header = out / "mine.glsl"
    header.write_text(header.read_text().replace("mine_reflect", "mine_reflekt", 1))
    assert cli_main(args + ["--check"]) == 1
    assert f"stale: {header}" in capsys.readouterr().out
    (out / "mine.wgsl").unlink()
    assert cli_main(args + ["--check"]) == 1
    assert "mine.wgsl does not exist" in capsys.readouterr().out


def test_target_headers_ignore_only_the_sympy_version(tmp_path, monkeypatch):
    with monkeypatch.context() as m:
        m.setattr(build.sympy, "__version__", "0.0.0-other")
        files = build.render(("numba", "c", "wgsl"))
    assert any("sympy: 0.0.0-other" in line for line in files["c/cgaskin.h"].splitlines()[:12])
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text, encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 0, "\n".join(messages)
    wgsl = tmp_path / "wgsl" / "cgaskin.wgsl"
    wgsl.write_text(wgsl.read_text().replace("spec hash: ", "spec hash: 0", 1))
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 1
    assert "generated/wgsl/cgaskin.wgsl" in messages[0]


@pytest.mark.parametrize("value", ["metal", "c,,hlsl", ""])
def test_an_unknown_target_is_a_one_line_error(value, capsys):
    assert cli_main(["build", "--check", "--target", value]) == 2
    err = capsys.readouterr().err
    assert "unknown target" in err and "choose from numba, c, glsl, wgsl, cuda" in err
