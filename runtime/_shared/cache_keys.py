"""numba's on-disk cache, keyed by every cgaskin source a kernel is built from.

numba keys a cached kernel by the source of its own file only. A kernel compiles the helpers and
constants it imports from other modules into its machine code, so a changed helper in another file
would leave every kernel that uses it stale (an upgraded install, a developer's edit) with no error.
``install()`` makes the key of a kernel defined in cgaskin the digest of its own file and of every
cgaskin module it imports, transitively (read from the import statements, so constants count too);
functions outside cgaskin keep numba's key.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import re
import sys
from pathlib import Path

_PACKAGES = ("cgaskin",)


#: ``from .x import a, b`` (names in parentheses may span lines) and ``import x.y``, at any depth: a
#: regular expression (parsing every module's syntax tree cost a tenth of a second per process); one
#: that a docstring quotes only adds a module to the key
_IMPORT = re.compile(r"^[ \t]*(?:from[ \t]+([.\w]+)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*)|import[ \t]+([^\n]*))", re.M)


@functools.lru_cache(maxsize=None)
def _imports(module: str) -> tuple[str, ...]:
    """The cgaskin modules that ``module`` (a loaded module's name) imports, directly."""
    loaded = sys.modules[module]
    path, name = Path(loaded.__file__), loaded.__name__     # (its own name: ``cgaskin.versor`` is an alias)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
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
        found.update(name for name in names if name.split(".")[0] in _PACKAGES and _is_module(name))
    return tuple(sorted(found))


def _is_module(name: str) -> bool:
    """Whether ``name`` is a module (``from m import f`` names f too: a function is not one). The
    modules a loaded module imports are loaded too (a file-system search per name cost a third of a
    second per process)."""
    return name in sys.modules


@functools.lru_cache(maxsize=None)
def _module_of(py_file: str) -> str | None:
    """The name of the loaded cgaskin module whose source is ``py_file``, or None."""
    path = os.path.realpath(py_file)
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] in _PACKAGES and getattr(module, "__file__", None) \
                and os.path.realpath(module.__file__) == path:
            return module.__name__          # (not an alias's: the key must not depend on import order)
    return None


@functools.lru_cache(maxsize=None)
def _closure_digest(module: str) -> bytes:
    """sha256 over the sources of ``module`` and every cgaskin module it imports, transitively."""
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


def install() -> None:
    """Key cgaskin's cached kernels by their import closure (idempotent)."""
    from numba.core import caching
    mixin = caching._SourceFileBackedLocatorMixin
    if getattr(mixin.get_source_stamp, "_cgaskin", False):
        return
    numba_stamp = mixin.get_source_stamp

    def get_source_stamp(self):
        stamp = numba_stamp(self)
        module = _module_of(self._py_file)
        if module is None:
            return stamp
        return hashlib.sha256(repr(stamp).encode() + _closure_digest(module)).digest()

    get_source_stamp._cgaskin = True
    mixin.get_source_stamp = get_source_stamp
