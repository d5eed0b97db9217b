"""numba's cache keys a kernel by its own file; cgaskin's key also holds every cgaskin module the
kernel's module imports, so that a changed helper or constant in another file recompiles it. The key
is given to cgaskin's own dispatchers only (``_shared.cache_keys.keyed``), through numba internals that
``cache_keys.missing()`` names; this file fails, naming the one that is gone, on a numba without them."""
import importlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import pytest
from numba.core import caching

from cgaskin._shared import cache_keys
from cgaskin.errors import KernelCacheWarning
from cgaskin.surgery.tear import walk

NO_JIT = pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="no numba cache without the JIT")


def test_the_numba_internals_the_key_relies_on_are_there():
    what = cache_keys.missing()
    assert what is None, (f"numba {numba.__version__} lacks {what}: cgaskin's kernels would compile without "
                          "the on-disk cache; adapt runtime/_shared/cache_keys.py, or bound numba in pyproject.toml "
                          "to the versions that have it")


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
    # a module it does not import is not part of its key, nor is the module that computes the key
    assert "cgaskin.surgery.session" not in closure
    assert "cgaskin._shared.cache_keys" not in closure and "cgaskin._shared.jit" in closure


def _walk_stamp():
    return cache_keys.source_stamp("numba's stamp of walk.py", "cgaskin.surgery.tear.walk")


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


@NO_JIT
def test_cgaskins_dispatchers_use_the_key_and_nothing_else_does(tmp_path):
    assert type(walk._walk._cache).__name__ == "KernelCache" and cache_keys.is_keyed(walk._walk)
    assert type(walk._walk._cache.disk()).__name__ == "ClosureKeyedCache"
    assert walk._walk._cache.disk()._impl.locator.get_source_stamp() == \
        cache_keys.source_stamp(caching.FunctionCache(walk._walk.py_func)._impl.locator.get_source_stamp(),
                                "cgaskin.surgery.tear.walk")
    # numba's own classes are untouched: a function outside cgaskin keeps numba's cache and key
    source = tmp_path / "outside.py"
    source.write_text("def f():\n    return 1\n")
    spec = importlib.util.spec_from_file_location("outside_module", source)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    outside = numba.njit(cache=True)(module.f)
    assert type(outside._cache) is caching.FunctionCache
    assert caching._SourceFileBackedLocatorMixin.get_source_stamp.__module__ == "numba.core.caching"


def test_without_the_internals_kernels_compile_uncached_with_a_warning(monkeypatch):
    monkeypatch.setattr(caching.FunctionCache, "_impl_class", None)
    cache_keys._cache_class.cache_clear()
    cache_keys._disk_class.cache_clear()
    try:
        assert "_impl_class" in cache_keys.missing()
        with pytest.warns(KernelCacheWarning, match="compile without that cache"):
            dispatcher = cache_keys.keyed(numba.njit(lambda x: x + 1))
        if isinstance(dispatcher, numba.core.dispatcher.Dispatcher):
            assert not isinstance(dispatcher._cache, caching.Cache)
        assert dispatcher(1) == 2
    finally:
        monkeypatch.undo()
        cache_keys._cache_class.cache_clear()
        cache_keys._disk_class.cache_clear()


# a tiny package whose kernel calls a helper from another module, compiled by cgaskin's jit wrapper or,
# under another interpreter (another numba, without cgaskin installed), by njit + cache_keys.py loaded by path
JIT = {"cgaskin": "from cgaskin._shared.jit import helper, kernel\n",
       "by path": textwrap.dedent(f"""\
           import importlib.util, sys
           from numba import njit
           spec = importlib.util.spec_from_file_location("cache_keys", {cache_keys.__file__!r})
           keys = sys.modules[spec.name] = importlib.util.module_from_spec(spec)
           spec.loader.exec_module(keys)


           def helper(function):
               return keys.keyed(njit(nogil=True)(function))


           def kernel(*signatures):
               return helper
       """)}
HELPER = "from .jit import helper\n\n\n@helper\ndef shift(x):\n    return x + 1.0\n"
USER = "from .helper import shift\nfrom .jit import kernel\n\n\n@kernel()\ndef doubled(x):\n    return 2.0 * shift(x)\n"
PROBE = textwrap.dedent("""\
    import sys
    sys.path.insert(0, sys.argv[1])
    import numba
    from probe_pkg.user import doubled
    value = doubled(1.0)
    print(numba.__version__, value, sum(doubled.stats.cache_hits.values()), sum(doubled.stats.cache_misses.values()))
""")
#: interpreters with other numba versions to run the guarantee under, e.g. the oldest pyproject.toml allows
#: (``python -m venv v && v/bin/pip install numba==0.59.1 "numpy<2"``): paths separated by os.pathsep
OTHER_PYTHONS = [p for p in os.environ.get("CGASKIN_OTHER_NUMBAS", "").split(os.pathsep) if p]


@NO_JIT
@pytest.mark.parametrize("python, jit", [(sys.executable, "cgaskin")] + [(p, "by path") for p in OTHER_PYTHONS])
def test_editing_a_helper_recompiles_the_kernels_that_use_it(tmp_path, python, jit):
    package = tmp_path / "src" / "probe_pkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "jit.py").write_text(JIT[jit])
    (package / "helper.py").write_text(HELPER)
    (package / "user.py").write_text(USER)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    if jit == "by path":
        env.pop("PYTHONPATH", None)

    def run():
        done = subprocess.run([python, "-c", PROBE, str(tmp_path / "src")], env=env, capture_output=True, text=True)
        assert done.returncode == 0, done.stdout + done.stderr
        version, value, hits, misses = done.stdout.split()
        return float(value), int(hits), int(misses)

    assert run() == (4.0, 0, 1)                         # compiled, and saved
    assert run() == (4.0, 1, 0)                         # loaded from the cache
    # the same size, and user.py untouched: numba's own key of doubled would not change
    (package / "helper.py").write_text(HELPER.replace("x + 1.0", "x + 2.0"))
    assert run() == (6.0, 0, 1)                         # recompiled with the edited helper
    assert run() == (6.0, 1, 0)


PROBE_RECORD = PROBE.replace("value = doubled(1.0)", "from probe_pkg.records import Pair\nvalue = doubled(Pair(1.0, 0.0))")
RECORD = "from typing import NamedTuple\n\n\nclass Pair(NamedTuple):\n    x: float\n    y: float\n"
USER_ANY = USER.replace("shift(x)", "shift(x[0])")
PROBE_TUPLE = PROBE.replace("value = doubled(1.0)", "value = doubled((1.0, 0.0))")


@NO_JIT
def test_a_cache_written_with_a_type_since_removed_is_compiled_again(tmp_path):
    """numba reads a whole index before it compares its key: an index holding a signature whose record
    type lived in a module since removed (an upgrade) recompiles with a warning, instead of failing."""
    package = tmp_path / "src" / "probe_pkg"
    package.mkdir(parents=True)
    for name, text in (("__init__", ""), ("jit", JIT["cgaskin"]), ("helper", HELPER), ("user", USER_ANY),
                       ("records", RECORD)):
        (package / f"{name}.py").write_text(text)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def run(probe):
        done = subprocess.run([sys.executable, "-c", probe, str(tmp_path / "src")], env=env, capture_output=True,
                              text=True)
        assert done.returncode == 0, done.stdout + done.stderr
        version, value, hits, misses = done.stdout.split()
        return float(value), int(hits), int(misses), done.stderr

    assert run(PROBE_RECORD)[:3] == (4.0, 0, 1)          # compiled for Pair, saved
    (package / "records.py").unlink()
    value, hits, misses, stderr = run(PROBE_TUPLE)
    assert (value, hits, misses) == (4.0, 0, 1) and "KernelCacheWarning: cgaskin: the on-disk cache" in stderr
    assert run(PROBE_TUPLE)[:3] == (4.0, 1, 0)           # the new index loads
