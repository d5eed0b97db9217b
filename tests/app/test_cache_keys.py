"""numba's cache keys a kernel by its own file; cgaskin's key also holds every cgaskin module the
kernel's module imports, so that a changed helper or constant in another file recompiles it."""
import importlib
from pathlib import Path

from numba.core import caching

from cgaskin._shared import cache_keys
from cgaskin.surgery.tear import walk


def _walk_stamp():
    locator = caching.InTreeCacheLocator.from_function(walk._walk.py_func, walk.__file__)
    return locator.get_source_stamp()


def test_a_kernel_depends_on_the_helpers_and_constants_it_imports():
    closure = set()
    stack = ["cgaskin.surgery.tear.walk"]
    while stack:
        name = stack.pop()
        if name not in closure:
            closure.add(name)
            stack.extend(cache_keys._imports(name))
    # walk's helpers (junctions, elements), the node kinds it compiles in as constants (records), the
    # BVH query it calls
    assert {"cgaskin.surgery.tear.junctions", "cgaskin.surgery.tear.elements", "cgaskin.surgery.tear.records",
            "cgaskin.surgery.bvh"} <= closure
    # a module it does not import is not part of its key
    assert "cgaskin.surgery.session" not in closure


def test_a_changed_helper_changes_the_key_of_the_kernels_that_use_it(monkeypatch):
    before = _walk_stamp()
    assert before == _walk_stamp()                      # a key, not a fresh value per call
    helper_file = Path(importlib.import_module("cgaskin.surgery.tear.junctions").__file__).resolve()
    original = Path.read_bytes

    def edited(path):
        data = original(path)
        return data + b"\n# an edit\n" if path.resolve() == helper_file else data

    monkeypatch.setattr(Path, "read_bytes", edited)
    _forget_digests()
    try:
        assert _walk_stamp() != before
    finally:
        monkeypatch.undo()
        _forget_digests()
    assert _walk_stamp() == before


def _forget_digests():
    """Read the sources again (the digests are kept per process)."""
    cache_keys._closure_digest.cache_clear()
    cache_keys._source_digest.cache_clear()


def test_functions_outside_cgaskin_keep_numbas_key(tmp_path):
    source = tmp_path / "outside.py"
    source.write_text("def f():\n    return 1\n")
    spec = importlib.util.spec_from_file_location("outside_module", source)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    locator = caching.InTreeCacheLocator.from_function(module.f, str(source))
    assert locator.get_source_stamp() == caching._hash_source_file(str(source), source.stat().st_mtime,
                                                                   source.stat().st_size)
