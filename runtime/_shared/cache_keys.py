"""The cache of cgaskin's kernels: the kernels shipped compiled first, then numba's on-disk cache keyed
by every cgaskin source a kernel is built from.

numba keys a cached function by the source of its own file only. A kernel compiles the helpers and
constants it imports from other modules into its machine code, so a changed helper in another file
would leave every kernel that uses it stale (an upgraded install, a developer's edit) with no error.
``keyed(dispatcher)``, which ``_shared.jit`` calls on each dispatcher it makes (and on the generated
ones), gives that dispatcher a cache that asks the shipped kernels first (``_shared.shipped``, keyed
the same way), then numba's on-disk cache with numba's key plus the digest of the kernel's module and
of every module of its package that it imports, transitively (read from the import statements, so
constants count too). numba's on-disk cache of a kernel is made at its first use (numba makes its
folder then: a process that runs only shipped kernels writes nothing), and where no folder can hold it
kernels compile in memory. Every entry loaded is checked against the signature asked for. Nothing
global changes: numba's classes and other libraries' functions keep numba's cache and key.

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

from ..errors import KernelCacheWarning


#: ``from .x import a, b`` (names in parentheses may span lines) and ``import x.y``, at any depth: a
#: regular expression (parsing every module's syntax tree cost a tenth of a second per process); one
#: that a docstring quotes only adds a module to the key
_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+([.\w]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+([^\n]*))", re.M)


#: the modules that key and load kernels but compile into none: editing them must not recompile them all
_KEYING = (__name__, f"{__name__.rpartition('.')[0]}.shipped")


@functools.lru_cache(maxsize=None)
def _imports(module: str) -> tuple[str, ...]:
    """The modules of ``module``'s own package (its top-level name) that it imports, directly."""
    path, name = module_file(module), module
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
        found.update(name for name in names if name.split(".")[0] == top and name not in _KEYING and _is_module(name))
    return tuple(sorted(found))


def _is_module(name: str) -> bool:
    """Whether ``name`` is a module (``from m import f`` names f too: a function is not one)."""
    return module_file(name) is not None


@functools.lru_cache(maxsize=None)
def module_file(name: str) -> Path | None:
    """The source file of module ``name``, loaded or not (a module imported lazily, inside a function,
    is part of a kernel's key too), or None when ``name`` is no module of a loaded package. A lookup
    beside the parent package's files, not importlib's search (a third of a second per process)."""
    loaded = sys.modules.get(name)
    if loaded is not None:
        file = getattr(loaded, "__file__", None)
        return Path(file) if file else None
    parent, _, last = name.rpartition(".")
    for folder in getattr(sys.modules.get(parent), "__path__", ()):
        for candidate in (Path(folder, f"{last}.py"), Path(folder, last, "__init__.py")):
            if candidate.is_file():
                return candidate
    return None


def closure(module: str) -> tuple[str, ...]:
    """``module`` and every module of its package it imports, transitively, by their own names, sorted."""
    seen, stack = set(), [module]
    while stack:
        name = stack.pop()
        name = getattr(sys.modules.get(name), "__name__", name)     # (aliases as the module's own name)
        if name in seen:
            continue
        seen.add(name)
        stack.extend(_imports(name))
    return tuple(sorted(seen))


@functools.lru_cache(maxsize=None)
def _closure_digest(module: str) -> bytes:
    """sha256 over the sources of ``module`` and every module of its package it imports, transitively."""
    digest = hashlib.sha256()
    for name in closure(module):
        digest.update(name.encode() + _source_digest(name))
    return digest.digest()


@functools.lru_cache(maxsize=None)
def _source_digest(module: str) -> bytes:
    """sha256 of a module's source (read once per process, whatever closures hold it)."""
    return hashlib.sha256(module_file(module).read_bytes()).digest()


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
def _disk_class():
    """numba's ``FunctionCache`` with its locator keyed by the function's closure, or None (``missing``)."""
    what = missing()
    if what is not None:
        import numba
        warnings.warn(f"cgaskin: numba {numba.__version__} lacks {what}, which cgaskin keys its kernels' on-disk "
                      "cache with; its kernels compile without that cache (every process compiles them again)",
                      KernelCacheWarning, stacklevel=4)
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
                cres = super().load_overload(sig, target_context)
            except (ImportError, AttributeError, pickle.UnpicklingError) as exc:
                # numba unpickles an index before it compares its key: an index that another version
                # wrote with a type of a module or class since removed cannot load, and is stale anyway
                _forget(self, exc)
                return None
            if cres is not None and tuple(cres.signature.args) != argument_types(sig):
                # two processes writing one index at once can file an entry under another signature:
                # compile it (numba then saves the right entry under this key)
                return None
            return cres

    return ClosureKeyedCache


@functools.lru_cache(maxsize=None)
def _cache_class():
    """The cache ``keyed`` gives a dispatcher, or None (``missing``): the shipped kernels first (when
    given), then numba's on-disk cache keyed by the closure, made at its first use (making it makes
    its folder: a process that loads every kernel it runs from the shipped ones writes nothing)."""
    disk_class = _disk_class()
    if disk_class is None:
        return None
    from numba.core import caching

    class KernelCache(caching._Cache):
        def __init__(self, py_func, shipped=None):
            self._py_func, self._shipped, self._enabled = py_func, shipped, True
            self._name = repr(py_func)
            self._disk_cache = None

        def disk(self):
            """numba's cache of this function, or None when no folder can hold it (no writable
            ``__pycache__``, ``NUMBA_CACHE_DIR`` or user cache folder: what compiles stays in memory)."""
            if self._disk_cache is None:
                try:
                    self._disk_cache = disk_class(self._py_func)
                except RuntimeError:                # numba: "no locator available"
                    self._disk_cache = False
            return self._disk_cache or None

        @property
        def cache_path(self):
            disk = self.disk()
            return None if disk is None else disk.cache_path

        def load_overload(self, sig, target_context):
            if not self._enabled:
                return None
            why = None
            if self._shipped is not None:
                cres, why = self._shipped.load(self._py_func, argument_types(sig), target_context)
                if cres is not None:
                    return cres
            disk = self.disk()
            cres = None if disk is None else disk.load_overload(sig, target_context)
            if cres is None and self._shipped is not None:
                self._shipped.compiling(self._py_func, why)
            return cres

        def save_overload(self, sig, data):
            disk = self.disk()
            if self._enabled and disk is not None:
                disk.save_overload(sig, data)

        def enable(self):
            self._enabled = True

        def disable(self):
            self._enabled = False

        def flush(self):
            disk = self.disk()
            if disk is not None:
                disk.flush()

    return KernelCache


def argument_types(sig) -> tuple:
    """The argument types of a signature as numba passes it to a cache (types, or a ``Signature``)."""
    from numba.core import sigutils
    return tuple(sigutils.normalize_signature(sig)[0])


def _forget(cache, why: Exception) -> None:
    """Remove ``cache``'s index (its functions compile again and save a new one), with a warning."""
    path = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
    warnings.warn(f"cgaskin: the on-disk cache of {cache._name} could not be read ({type(why).__name__}: {why}); "
                  "compiling it again", KernelCacheWarning, stacklevel=2)
    if path is not None:
        Path(path).unlink(missing_ok=True)


def is_keyed(dispatcher) -> bool:
    """Whether ``keyed`` gave ``dispatcher`` its cache."""
    cache = _cache_class()
    return cache is not None and isinstance(getattr(dispatcher, "_cache", None), cache)


def keyed(dispatcher, shipped=None):
    """Give ``dispatcher`` (a numba dispatcher) the on-disk cache keyed by its closure; returns it.
    ``shipped``, when given, is asked first (``shipped.load(py_func, argument_types, target_context)``
    returns numba's compile result or None, and why), and told when the function compiles after all
    (``shipped.compiling(py_func, why)``): ``_shared.shipped``'s loaders. A plain function
    (``NUMBA_DISABLE_JIT=1``) is returned as it is."""
    from numba.core.dispatcher import Dispatcher
    if isinstance(dispatcher, Dispatcher):
        cache = _cache_class()
        if cache is not None:
            dispatcher._cache = cache(dispatcher.py_func, shipped)    # what enable_caching() does, with ours
    return dispatcher
