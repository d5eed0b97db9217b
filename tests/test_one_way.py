"""One way to do a thing (issue 43 D17): a file written whole through one helper, one ``PoseSpec``, a
session's splice written from records rather than 21 positional arguments."""
import ast
import inspect
import pkgutil
from pathlib import Path

import pytest

import cgaskin

PACKAGE = Path(cgaskin.__file__).resolve().parent


def _sources():
    for path in sorted(PACKAGE.rglob("*.py")):
        if "_kernels" not in path.parts:
            yield path, ast.parse(path.read_text(encoding="utf-8"))


def test_one_temporary_file_then_rename_write():
    """``os.replace`` appears once in the package: in the helper every whole-file write goes through."""
    calls = [f"{path.relative_to(PACKAGE)}:{node.lineno}" for path, tree in _sources() for node in ast.walk(tree)
             if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "replace"
             and isinstance(node.func.value, ast.Name) and node.func.value.id == "os"]
    assert calls == ["_shared/atomic.py:" + calls[0].split(":")[1]], calls


def test_a_write_that_fails_leaves_the_old_file_and_no_temporary(tmp_path):
    from cgaskin._shared.atomic import replaced
    path = tmp_path / "manifest.parquet"
    path.write_bytes(b"old")
    with pytest.raises(KeyboardInterrupt):
        with replaced(path) as temporary:
            temporary.write_bytes(b"half")
            raise KeyboardInterrupt
    assert path.read_bytes() == b"old" and [p.name for p in tmp_path.iterdir()] == ["manifest.parquet"]
    with replaced(path) as temporary:
        assert temporary.parent == tmp_path and temporary.suffix == ".parquet"
        temporary.write_bytes(b"new")
    assert path.read_bytes() == b"new" and [p.name for p in tmp_path.iterdir()] == ["manifest.parquet"]


def test_one_pose_spec_class():
    """The server's ``PoseSpec`` (a pose a page showed) is the only class of that name; the batch spec's
    [[poses]] table is a ``PoseEntry`` (a clip at several times, edits drawn per item)."""
    import cgaskin.batch.spec  # noqa: F401  (the modules that define classes)
    import cgaskin.serve.protocol  # noqa: F401
    found = set()
    for info in pkgutil.walk_packages(cgaskin.__path__, "cgaskin."):
        module = __import__("sys").modules.get(info.name)
        if module is None:
            continue
        for name, obj in vars(module).items():
            if inspect.isclass(obj) and obj.__name__ == "PoseSpec" and obj.__module__.startswith("cgaskin"):
                found.add(f"{obj.__module__}.{obj.__qualname__}")
    assert found == {"cgaskin.serve.protocol.PoseSpec"}
    from cgaskin.batch.spec import PoseEntry
    assert PoseEntry.__name__ == "PoseEntry"


def test_a_splice_is_written_from_records():
    """``session_write._write_splice`` took 21 positional arguments; now the session's buffers and the
    splice's rows, each a record (a plain tuple to the kernel), and it returns one."""
    from cgaskin.surgery import session_write
    assert list(inspect.signature(session_write._write_splice.py_func).parameters) == ["buffers", "n", "m", "splice"]
    session = cgaskin.Surgery(cgaskin.capsule_arm())
    session.tear(([0.6, 0.05, 1.0], [0.6, 0.05, 0.0]), ([1.2, 0.05, 1.0], [1.2, 0.05, 0.0]), opening=0.05)
    assert session.rig.n_vertices > cgaskin.capsule_arm().n_vertices
