"""The layout keeps its promises: imports run one way through the layers, no import circle, no
module over about 400 lines, and production code never imports the test oracles (baselines)."""
import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: folder -> package, as pyproject.toml maps them
PACKAGES = {"runtime": "cgaskin", "rigs": "cgaskin.rigs", "codegen": "cgaskin.codegen",
            "generated": "cgaskin.generated"}
#: layers, lowest first: a module may import its own layer and the ones below it only
LAYERS = [("cgaskin.errors", "cgaskin.tolerances", "cgaskin._shared", "cgaskin.generated"),
          ("cgaskin.algebra",),
          ("cgaskin.animation",),
          ("cgaskin.rigs", "cgaskin.surgery"),
          ("cgaskin.app", "cgaskin.batch", "cgaskin.view", "cgaskin.serve", "cgaskin.codegen"),
          ("cgaskin", "cgaskin.__main__")]
MAX_LINES = 420


def _modules() -> dict:
    """module name -> path of every module of the package (generated code included)."""
    out = {}
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package] + parts)] = path
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> set:
    """The cgaskin modules that ``name`` imports, at module level or inside functions."""
    is_package = path.name == "__init__.py"
    base = name.split(".") if is_package else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                stem = ".".join(base[:len(base) - node.level + 1] + ([node.module] if node.module else []))
            else:
                stem = node.module or ""
            # `from package import module` imports the module; `from module import name` the module
            targets = [f"{stem}.{alias.name}" if f"{stem}.{alias.name}" in MODULES else stem
                       for alias in node.names]
        else:
            continue
        found.update(t for t in targets if t in MODULES and t != name)
    return found


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def _layer(name: str) -> int:
    best, rank = -1, None
    for r, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best:
                best, rank = len(prefix), r
    return rank


def test_every_module_has_a_layer():
    assert [name for name in MODULES if name != "cgaskin.baselines" and _layer(name) is None] == []


def test_imports_run_down_the_layers():
    upward = [(a, b) for a, targets in GRAPH.items() for b in targets
              if a != "cgaskin.baselines" and b != "cgaskin.baselines" and _layer(b) > _layer(a)]
    assert upward == []


def test_no_import_circle():
    state, stack, circles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for target in sorted(GRAPH[node]):
            if state.get(target) == "open":
                circles.append(stack[stack.index(target):] + [target])
            elif target not in state:
                visit(target)
        stack.pop()
        state[node] = "done"

    for node in sorted(GRAPH):
        if node not in state:
            visit(node)
    assert circles == []


def test_production_never_imports_the_oracles():
    importers = sorted(a for a, targets in GRAPH.items() if "cgaskin.baselines" in targets)
    assert importers == []
    assert GRAPH["cgaskin.baselines"] <= {"cgaskin.errors"}


@pytest.mark.parametrize("name", sorted(n for n in MODULES if not n.startswith("cgaskin.generated")))
def test_modules_stay_small(name):
    lines = len(MODULES[name].read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{MODULES[name].relative_to(ROOT)} has {lines} lines: split it by job"
