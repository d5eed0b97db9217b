"""Operation counts (codegen/opcount.py, `cgaskin build --report`): counted as the printers emit the
kernel after CSE, checked against counts done by hand."""
import textwrap

from cgaskin.app.cli import main as cli_main
from cgaskin.codegen import catalogue
from cgaskin.codegen.opcount import op_counts


def test_affine_point_counts_three_rows_of_three_products_and_three_sums():
    kernel = catalogue.affine_point()
    assert op_counts(kernel) == {"mul": 9, "add": 9, "div": 0, "sqrt": 0, "other": 0}


def test_the_report_counts_a_user_kernel_and_its_hoisted_parts(tmp_path, capsys):
    source = tmp_path / "k.py"
    source.write_text(textwrap.dedent('''
        from cgaskin.codegen import cga, kernel

        @kernel
        def vv(a: cga.Vector, b: cga.Vector) -> cga.Multivector["s", "e12", "e13", "e23"]:
            """a b: the scalar a·b (3 mul, 2 add) and three bivector parts (2 mul, 1 add each)."""
            return a * b

        @kernel
        def unit(a: cga.Vector) -> cga.Vector:
            return a / cga.sqrt(a | a)

        @kernel(uniform=("V",))
        def move(V: cga.Versor, x: cga.Point) -> cga.Point:
            return V * x * ~V
    '''), encoding="utf-8")
    assert cli_main(["build", "--catalogue", str(source), "--out", str(tmp_path / "out"), "--report"]) == 0
    lines = capsys.readouterr().out.splitlines()[1:]
    rows = {" ".join(line.split()[:2]) if line.startswith(" ") else line.split()[0]:
            line.split()[2:] if line.startswith(" ") else line.split()[1:] for line in lines if line.strip()}
    assert rows["vv"][:6] == ["9", "5", "0", "0", "0", "14"]
    # a / sqrt(a·a): 3 mul + 2 add for a·a, one sqrt, one division, then 3 products by it
    assert rows["unit"][:6] == ["6", "2", "1", "1", "0", "10"]
    # the versor sandwich per row is an affine map: 9 mul, 9 add
    assert rows["per row"][:6] == ["9", "9", "0", "0", "0", "18"]


def test_the_built_in_report_lists_every_kernel(capsys):
    assert cli_main(["build", "--check", "--report"]) == 0
    out = capsys.readouterr().out
    names = [line.split()[0] for line in out.splitlines()[1:] if line and not line.startswith("generated/")]
    assert names == [make.__name__ for make in catalogue.KERNELS]
