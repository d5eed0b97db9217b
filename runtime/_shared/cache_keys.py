"""numba's on-disk cache, keyed by every cgaskin source a kernel is built from.

numba keys a cached kernel by the source of its own file only. A kernel compiles the helpers and
constants it imports from other modules into its machine code, so a changed helper in another file
would leave every kernel that uses it stale (an upgraded install, a developer's edit) with no error.
``install()`` makes the key of a kernel defined in cgaskin the digest of its own file and of every
cgaskin module it imports, transitively (read from the import statements, so constants count too);
functions outside cgaskin keep numba's key.
"""
from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import os
import sys
from pathlib import Path

_PACKAGES = ("cgaskin",)


@functools.lru_cache(maxsize=None)
def _imports(module: str) -> tuple[str, ...]:
    """The cgaskin modules that ``module`` (a loaded module's name) imports, directly."""
    spec = importlib.util.find_spec(module)
    path = Path(spec.origin)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.ImportFrom):
            base = importlib.util.resolve_name("." * node.level + (node.module or ""), package) \
                if node.level else (node.module or "")
            names = [base] + [f"{base}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        found.update(name for name in names if name.split(".")[0] in _PACKAGES and _is_module(name))
    return tuple(sorted(found))


def _is_module(name: str) -> bool:
    """Whether ``name`` is a module (``from m import f`` names f too: a function is not one)."""
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


@functools.lru_cache(maxsize=None)
def _module_of(py_file: str) -> str | None:
    """The name of the loaded cgaskin module whose source is ``py_file``, or None."""
    path = os.path.realpath(py_file)
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] in _PACKAGES and getattr(module, "__file__", None) \
                and os.path.realpath(module.__file__) == path:
            return name
    return None


@functools.lru_cache(maxsize=None)
def _closure_digest(module: str) -> bytes:
    """sha256 over the sources of ``module`` and every cgaskin module it imports, transitively."""
    seen, stack = set(), [module]
    while stack:
        name = stack.pop()
        if name in seen:
            continue
        seen.add(name)
        stack.extend(_imports(name))
    digest = hashlib.sha256()
    for name in sorted(seen):
        digest.update(name.encode())
        digest.update(Path(importlib.util.find_spec(name).origin).read_bytes())
    return digest.digest()


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
