"""The performance page's tables are what the benchmark scripts wrote (issue 44): every file under
``docs/performance`` carries the header ``benchmarks/_report.py`` writes (the command that made it,
naming that very file, the machine, the commit, the date, the load), every script the page's README
names takes ``--write`` through the shared helper, and the helper writes what the script printed (and
nothing when the run fails). No benchmark runs here: the scripts are read as syntax trees."""
import ast
import re
from pathlib import Path

import pytest

from benchmarks import _report

ROOT = Path(__file__).resolve().parents[1]
TABLES = ROOT / "docs" / "performance"
FILES = sorted(TABLES.glob("*.txt"))
#: README's table: | NAME.txt | `benchmarks/SCRIPT.py` |
LISTED = re.findall(r"^\| (\w+\.txt) \| `benchmarks/(\w+)\.py` \|$", (TABLES / "README.md").read_text(), re.M)
SCRIPTS = sorted(p for p in (ROOT / "benchmarks").glob("*.py") if not p.name.startswith("_"))


def _header(path: Path) -> dict:
    fields = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if not line.startswith("# "):
            break
        name, _, value = line[2:].partition(": ")
        fields[name] = value
    return fields


def test_the_readme_lists_scripts_that_exist():
    assert len(LISTED) >= 12
    for table, script in LISTED:
        assert (ROOT / "benchmarks" / f"{script}.py").is_file(), f"{table}: benchmarks/{script}.py is missing"


@pytest.mark.parametrize("table, script", LISTED, ids=[t for t, _ in LISTED])
def test_every_listed_table_is_written(table, script):
    assert (TABLES / table).is_file(), (f"docs/performance/{table} is not written: "
                                        f"python -m benchmarks.{script} --write docs/performance/{table}")


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_a_table_file_says_what_made_it(path):
    fields = _header(path)
    assert tuple(fields) == _report.HEADER_FIELDS, f"{path.name}: header fields {tuple(fields)}"
    script = dict((t, s) for t, s in LISTED).get(path.name)
    assert script, f"{path.name} is not in docs/performance/README.md's table"
    command = fields["command"].split()
    assert command[:3] == ["python", "-m", f"benchmarks.{script}"], fields["command"]
    assert command[command.index("--write") + 1] == f"docs/performance/{path.name}", fields["command"]
    assert re.fullmatch(r"[0-9a-f]{7,40}(\+dirty)?", fields["commit"]), fields["commit"]
    assert re.search(r"\d+ cores .*Python 3\.\d+\.\d+, numba \d+\.\d+\.\d+, NumPy \d+\.\d+\.\d+", fields["machine"])
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d[+-]\d\d:\d\d", fields["date"]), fields["date"]
    body = path.read_text(encoding="utf-8").split("\n\n", 1)[1]
    assert body.strip(), f"{path.name} has a header and no table"


def _takes_write(path: Path) -> bool:
    """``main`` is decorated with ``writes_tables`` and builds its parser with ``benchmark_parser``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    main = next((n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "main"), None)
    if main is None:
        return False
    decorated = any(isinstance(d, ast.Name) and d.id == "writes_tables" for d in main.decorator_list)
    parser = any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "benchmark_parser"
                 for n in ast.walk(main))
    return decorated and parser


@pytest.mark.parametrize("path", SCRIPTS, ids=[p.stem for p in SCRIPTS])
def test_every_benchmark_script_takes_write(path):
    assert _takes_write(path), (f"benchmarks/{path.name}: decorate main with _report.writes_tables and build "
                                f"its parser with _report.benchmark_parser (that gives it --write)")


@_report.writes_tables
def _fake_main(argv=None):
    parser = _report.benchmark_parser(__doc__)
    parser.add_argument("--fail", action="store_true")
    args = parser.parse_args(argv)
    print("\ntable\n-----\nrow 1")
    if args.fail:
        raise RuntimeError("the benchmark failed")


def test_write_keeps_what_is_printed_under_the_header(tmp_path, capsys):
    target = tmp_path / "out" / "fake.txt"
    _fake_main(["--write", str(target)])
    assert "row 1" in capsys.readouterr().out                  # still printed
    text = target.read_text(encoding="utf-8")
    fields = _header(target)
    assert tuple(fields) == _report.HEADER_FIELDS
    assert fields["command"] == f"python -m benchmarks.test_benchmark_files --write {target}"
    assert text.endswith("\n\ntable\n-----\nrow 1\n")


def test_a_failed_run_writes_nothing(tmp_path):
    target = tmp_path / "fake.txt"
    with pytest.raises(RuntimeError):
        _fake_main(["--write", str(target), "--fail"])
    assert not target.exists()


def test_without_write_nothing_is_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    _fake_main([])
    assert "row 1" in capsys.readouterr().out
    assert list(tmp_path.iterdir()) == []
