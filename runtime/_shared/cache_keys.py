"""numba's on-disk cache for cgaskin's kernels, keyed by every cgaskin source a kernel is built from.

numba keys a cached function by the source of its own file only. A kernel compiles the helpers and
constants it imports from other modules into its machine code, so a changed helper in another file
would leave every kernel that uses it stale (an upgraded install, a developer's edit) with no error.
``keyed(dispatcher)``, which ``_shared.jit`` calls on each dispatcher it makes, gives that dispatcher a
cache whose key is numba's key plus the digest of the kernel's module and of every module of its
package that it imports, transitively (read from the import statements, so constants count too).
Nothing global changes: numba's classes, other libraries' functions and generated/'s kernels (whose
stamped headers carry the hashes of what they import) keep numba's key.

The numba internals this relies on (``missing()`` checks them; tests/app/test_cache_keys.py fails
naming the one that is gone):
  * a dispatcher loads from and saves to ``dispatcher._cache``, which ``enable_caching()`` sets to a
    ``numba.core.caching.FunctionCache`` (numba's CUDA target installs its own cache class the same way);
  * a ``Cache`` builds its implementation from the class attribute ``_impl_class`` (the extension point
    its docstring names) and keys its index by ``self._impl.locator.get_source_stamp()``.
Both hold from numba 0.59 to 0.68 at least. Where they do not, kernels compile without the on-disk
cache, with a warning: slower, never stale.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import pickle
import re
import sys
import warnings
from pathlib import Path


#: ``from .x import a, b`` (names in parentheses may span lines) and ``import x.y``, at any depth: a
#: regular expression (parsing every module's syntax tree cost a tenth of a second per process); one
#: that a docstring quotes only adds a module to the key
_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+([.\w]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+([^\n]*))", re.M)


@functools.lru_cache(maxsize=None)
def _imports(module: str) -> tuple[str, ...]:
    """The modules of ``module``'s own package (its top-level name) that it imports, directly."""
    loaded = sys.modules[module]
    path, name = Path(loaded.__file__), loaded.__name__     # (its own name: ``cgaskin.versor`` is an alias)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    top = name.split(".")[0]
    found = set()
    for source, imported, modules in _IMPORT.findall(path.read_text(encoding="utf-8")):
        if source:
            dots = len(source) - len(source.lstrip("."))
            try:
                base = importlib.util.resolve_name(source, package) if dots else source
            except ImportError:
                continue
            names = [base] + [f"{base}.{item.split()[0]}" for item in imported.strip("()").replace("\\", " ").split(",")
                              if item.split()]
        else:
            names = [item.split()[0] for item in modules.split(",") if item.split()]
        # (this module keys kernels but compiles into none: editing it must not recompile them all)
        found.update(name for name in names if name.split(".")[0] == top and name != __name__ and _is_module(name))
    return tuple(sorted(found))


def _is_module(name: str) -> bool:
    """Whether ``name`` is a module (``from m import f`` names f too: a function is not one). The
    modules a loaded module imports are loaded too (a file-system search per name cost a third of a
    second per process)."""
    return name in sys.modules


@functools.lru_cache(maxsize=None)
def _closure_digest(module: str) -> bytes:
    """sha256 over the sources of ``module`` and every module of its package it imports, transitively."""
    seen, stack = set(), [module]
    while stack:
        name = sys.modules[stack.pop()].__name__        # (aliases as the module's own name)
        if name in seen:
            continue
        seen.add(name)
        stack.extend(_imports(name))
    digest = hashlib.sha256()
    for name in sorted(seen):
        digest.update(name.encode() + _source_digest(name))
    return digest.digest()


@functools.lru_cache(maxsize=None)
def _source_digest(module: str) -> bytes:
    """sha256 of a loaded module's source (read once per process, whatever closures hold it)."""
    return hashlib.sha256(Path(sys.modules[module].__file__).read_bytes()).digest()


def source_stamp(numba_stamp, module: str):
    """The key of a kernel of ``module``: numba's stamp of its file and the digest of its closure."""
    if getattr(sys.modules.get(module), "__file__", None) is None:
        return numba_stamp                               # (not a module read from a file: numba's key)
    return hashlib.sha256(repr(numba_stamp).encode() + _closure_digest(module)).digest()


class _KeyedLocator:
    """A numba cache locator whose source stamp is ``source_stamp``; the rest is the locator's."""

    def __init__(self, locator, module: str):
        self._locator, self._module = locator, module

    def __getattr__(self, name):
        return getattr(self._locator, name)

    def get_source_stamp(self):
        return source_stamp(self._locator.get_source_stamp(), self._module)


def missing() -> str | None:
    """The numba internal (see the module docstring) this numba lacks, or None when all are there."""
    try:
        from numba.core import caching
        from numba.core.dispatcher import Dispatcher
    except ImportError as exc:
        return f"numba.core.caching / numba.core.dispatcher ({exc})"
    impl = getattr(getattr(caching, "FunctionCache", None), "_impl_class", None)
    if not isinstance(impl, type):
        return "numba.core.caching.FunctionCache._impl_class"
    if not isinstance(getattr(impl, "locator", None), property):
        return f"the property {impl.__name__}.locator"
    if not callable(getattr(Dispatcher, "enable_caching", None)):
        return "numba.core.dispatcher.Dispatcher.enable_caching (which sets dispatcher._cache)"
    return None


@functools.lru_cache(maxsize=None)
def _cache_class():
    """A ``FunctionCache`` whose locator is keyed by the function's closure, or None (see ``missing``)."""
    what = missing()
    if what is not None:
        import numba
        warnings.warn(f"cgaskin: numba {numba.__version__} lacks {what}, which cgaskin keys its kernels' on-disk "
                      "cache with; its kernels compile without that cache (every process compiles them again)",
                      RuntimeWarning, stacklevel=3)
        return None
    from numba.core import caching

    class ClosureKeyedImpl(caching.FunctionCache._impl_class):
        def __init__(self, py_func):
            self._module = py_func.__module__      # (first: the base's __init__ reads the locator)
            super().__init__(py_func)

        @property
        def locator(self):
            return _KeyedLocator(super().locator, self._module)

    class ClosureKeyedCache(caching.FunctionCache):
        _impl_class = ClosureKeyedImpl

        def load_overload(self, sig, target_context):
            try:
                return super().load_overload(sig, target_context)
            except (ImportError, AttributeError, pickle.UnpicklingError) as exc:
                # numba unpickles an index before it compares its key: an index that another version
                # wrote with a type of a module or class since removed cannot load, and is stale anyway
                _forget(self, exc)
                return None

    return ClosureKeyedCache


def _forget(cache, why: Exception) -> None:
    """Remove ``cache``'s index (its functions compile again and save a new one), with a warning."""
    path = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
    warnings.warn(f"cgaskin: the on-disk cache of {cache._name} could not be read ({type(why).__name__}: {why}); "
                  "compiling it again", RuntimeWarning, stacklevel=2)
    if path is not None:
        Path(path).unlink(missing_ok=True)


def keyed(dispatcher):
    """Give ``dispatcher`` (a numba dispatcher made without ``cache=True``) the on-disk cache keyed by its
    closure; returns it. A plain function (``NUMBA_DISABLE_JIT=1``) is returned as it is."""
    from numba.core.dispatcher import Dispatcher
    if isinstance(dispatcher, Dispatcher):
        cache = _cache_class()
        if cache is not None:
            dispatcher._cache = cache(dispatcher.py_func)      # what enable_caching() does, with our class
    return dispatcher
