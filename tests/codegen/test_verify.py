"""Verification for free (codegen/verify.py, `cgaskin verify`): every kernel of a catalogue run as the
generated module, as the same Python function on clifford multivectors, and as the float64 symbolic
expansion; disagreements and exceptions fail."""
import subprocess
import sys
import textwrap

import pytest

from cgaskin.app.cli import main as cli_main
from cgaskin.codegen import verify_catalogue
from cgaskin.codegen.ir import CodegenError
from cgaskin.codegen.verify import TOL_CLIFFORD, TOL_EXPANSION, VerificationError

from tests.helpers.catalogues import README_CATALOGUE as README


FRAGILE = '''
from cgaskin.codegen import cga, kernel

@kernel
def fragile(x: cga.Point) -> cga.Point:
    """Fine while traced symbolically, raises on clifford values."""
    if type(x.mv).__name__ == "CliffordMV":
        raise RuntimeError("only symbolic")
    return x
'''

OPERATORS = '''
from cgaskin.codegen import algebras, cga, kernel

ALL = cga.Multivector[[algebras.cga.blade_name(m) for m in range(32)]]
MV = cga.Multivector["s", "e1", "e2i", "e12", "e3o", "e13i", "eio", "e123io"]

@kernel
def ops(a: MV, b: MV) -> ALL:
    return (a | b) + a.dual() + (a * ~b).grade(2, 4) + (a ^ cga.e1) + 2 * cga.einf - cga.eo / 4
'''

FUNCTIONS = '''
from cgaskin.codegen import cga, kernel


@kernel
def normalize_plane(p: cga.Plane) -> cga.Plane:
    return p / cga.sqrt(p * p)

@kernel
def rotor(axis: cga.Vector, angle: cga.Scalar) -> cga.Rotor:
    return cga.cos(angle / 2) - cga.sin(angle / 2) * axis * cga.e1 * cga.e2 * cga.e3 / cga.sqrt(axis * axis)

@kernel
def safe_inverse(s: cga.Scalar) -> cga.Scalar:
    return cga.where(abs(s) > 1e-12, 1 / s, 0) + cga.log(cga.exp(s)) * cga.atan2(1, s)
'''


def _write(directory, name, text):
    path = directory / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def readme(tmp_path_factory):
    """(catalogue, out folder, report of 20 examples)."""
    root = tmp_path_factory.mktemp("verify")
    source = _write(root, "mykernels.py", README)
    out = root / "generated"
    return source, out, verify_catalogue(source, out=out, examples=20)


def test_readme_catalogue_verifies(readme):
    _, out, report = readme
    assert report.ok and [k.name for k in report.kernels] == ["reflect", "move"]
    for k in report.kernels:
        assert k.examples == 20
        assert k.err_clifford <= TOL_CLIFFORD and k.err_expansion <= max(TOL_EXPANSION, k.reach)
    table = report.table()
    assert "reflect" in table and "move" in table and "tolerances" in table
    assert (out / "mykernels.py").is_file()


def test_operators_agree_with_clifford(tmp_path):
    """| is the left contraction, dual X I⁻¹, grade, the constants: the same in both algebras."""
    report = verify_catalogue(_write(tmp_path, "ops_kernels.py", OPERATORS), examples=5)
    assert report.ok and report.kernels[0].err_clifford < 1e-13


def test_wrong_generated_kernel_fails(readme, tmp_path):
    source, out, _ = readme
    edited = tmp_path / "generated"
    edited.mkdir()
    text = (out / "mykernels.py").read_text(encoding="utf-8")
    start = text.index("return (", text.index("def reflect("))
    at = text.index(" + ", start)
    (edited / "mykernels.py").write_text(text[:at] + " - " + text[at + 3:], encoding="utf-8")
    with pytest.raises(VerificationError, match="reflect") as info:
        verify_catalogue(source, out=edited, examples=5, rebuild=False)
    assert "move" not in str(info.value) and "plane=" in str(info.value)
    assert not info.value.report.ok and info.value.report.kernels[1].ok


def test_raising_kernel_fails(tmp_path):
    with pytest.raises(VerificationError, match="fragile.*clifford raised RuntimeError: only symbolic"):
        verify_catalogue(_write(tmp_path, "fragile_kernels.py", FRAGILE), examples=3)


def test_missing_module_without_rebuild(readme, tmp_path):
    with pytest.raises(CodegenError, match="no generated module"):
        verify_catalogue(readme[0], out=tmp_path, examples=3, rebuild=False)


def test_cli(readme, tmp_path, capsys):
    source, out, _ = readme
    assert cli_main(["verify", "--catalogue", str(source), "--out", str(out), "--examples", "5"]) == 0
    printed = capsys.readouterr().out
    assert "reflect" in printed and "move" in printed and "ok" in printed
    fragile = _write(tmp_path, "fragile_cli.py", FRAGILE)
    assert cli_main(["verify", "--catalogue", str(fragile), "--examples", "2"]) == 1
    assert "FAIL" in capsys.readouterr().out
    assert cli_main(["verify", "--catalogue", str(tmp_path / "missing.py")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_import_cgaskin_loads_neither_sympy_nor_clifford():
    code = ("import sys, cgaskin, cgaskin.codegen; "
            "assert 'sympy' not in sys.modules and 'clifford' not in sys.modules, sorted(sys.modules)")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_scalar_functions_verify_three_ways(tmp_path):
    """sqrt, cos, sin, exp, log, atan2, abs, / by a scalar value and where on clifford values too."""
    report = verify_catalogue(_write(tmp_path, "function_kernels.py", FUNCTIONS), examples=10)
    assert report.ok and [k.name for k in report.kernels] == ["normalize_plane", "rotor", "safe_inverse"]
    assert all(k.err_clifford < 1e-12 and k.err_expansion < 1e-12 for k in report.kernels)
