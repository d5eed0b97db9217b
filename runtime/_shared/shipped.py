"""The kernels that ship compiled inside the package: loaded at a first call instead of compiled.

numba compiles a kernel at its first call: a first tear on a fresh machine would compile for a minute
or two. ``cgaskin build --kernels`` (``cgaskin.app.ship``) compiles every signature that ``precompile``
records for a portable x86-64 target (LLVM's ``generic`` CPU, no SVML, numba's default options; the
kernels ``jit.WIDE`` marks also for x86-64-v3, loaded where the CPU has its features) and keeps each
kernel's compile result, as numba's cache pickles it (object code, and the bitcode that callers
compiled later link against), in one file per kernel and CPU under ``cgaskin/_kernels/<layer>/``, with
a ``manifest.json``: the versions it was built for, the digest of each source module, and for each
kernel its key, its argument types and its files' sha256.

A kernel's cache (``cache_keys``) asks ``load`` for what the user's numba cache lacks. ``load`` returns
the compile result, rebuilt in this process's target context (numba's dispatcher then registers it as
on a cache hit, under numba's compiler lock), when

* a layer was built for this numba and llvmlite, NumPy (major.minor: numba's code depends on it),
  Python and platform, and numba's code-changing settings are their defaults (none of ``NUMBA_OPT``,
  ``NUMBA_BOUNDSCHECK``, ``NUMBA_DEBUGINFO``, ``NUMBA_CPU_NAME``, ``NUMBA_CPU_FEATURES`` set), and
  ``CGASKIN_SHIPPED_KERNELS`` is not ``0``;
* the kernel's key is this source tree's: the syntax trees (comments and docstrings left out) of its
  module and of every cgaskin module it imports, transitively (``cache_keys.closure``), and its
  argument types are among those shipped;
* its file's sha256 is the manifest's (checked before anything is unpickled), and the loaded entry's
  signature is the one asked for.

Otherwise it returns None, numba compiles the kernel as without this layer (into the user's cache),
and the first time in a process one line on stderr says what compiles and why. Nothing global
changes: the loaded machine code is plain x86-64, run by the process's JIT; every other function,
a user's own included, compiles for the host as before. What loads is counted in ``LOADED``.
"""
from __future__ import annotations

import ast
import collections
import functools
import hashlib
import json
import os
import pickle
import sys
import sysconfig
from pathlib import Path
from typing import NamedTuple

from . import cache_keys

__all__ = ["Loader", "FOR_KERNELS", "FOR_HELPERS", "LOADED", "setup", "layer_name", "signature_text", "sources_key",
           "syntax_digest", "ROOT", "FORMAT"]

#: the folder of the shipped layers (``cgaskin/_kernels``): one folder per layer, named by ``layer_name``
ROOT = Path(__file__).resolve().parent.parent / "_kernels"
#: the layout of a layer's files: a layer of another format is not read
FORMAT = 1
#: numba's settings that change the machine code of every function: variable -> (``numba.core.config``'s
#: name, its default)
CODE_SETTINGS = {"NUMBA_OPT": ("OPT", 3), "NUMBA_BOUNDSCHECK": ("BOUNDSCHECK", None),
                 "NUMBA_DEBUGINFO": ("DEBUGINFO_DEFAULT", 0), "NUMBA_CPU_NAME": ("CPU_NAME", None),
                 "NUMBA_CPU_FEATURES": ("CPU_FEATURES", None)}
#: switches the layer off (a benchmark of host-compiled code, say): ``CGASKIN_SHIPPED_KERNELS=0``
SWITCH = "CGASKIN_SHIPPED_KERNELS"
#: the CPUs kernels ship compiled for, best first, and the features (LLVM's names) each assumes: a
#: kernel loads for the first one whose features this machine has
CPUS = {"x86-64-v3": ("avx", "avx2", "bmi", "bmi2", "f16c", "fma", "lzcnt", "movbe", "xsave", "cx16", "popcnt",
                      "sahf", "sse3", "sse4.1", "sse4.2", "ssse3"),
        "generic": ()}

#: "module.function" -> how many of its signatures this process loaded from the layer
LOADED: collections.Counter = collections.Counter()


class Layer(NamedTuple):
    """A shipped layer that this process can load from."""

    folder: Path
    kernels: dict       # "module.function" -> {"key", "signatures", "files": {cpu: {"file", "sha256"}}}
    modules: dict       # module -> {"sha256": of its file, "syntax": syntax_digest of it}


def setup() -> dict:
    """What a layer must have been built for to load in this process."""
    import llvmlite
    import numba
    import numpy
    return {"python": f"{sys.implementation.name} {sys.version_info[0]}.{sys.version_info[1]}{sys.abiflags}",
            "platform": sysconfig.get_platform(), "numba": numba.__version__, "llvmlite": llvmlite.__version__,
            "numpy": ".".join(numpy.__version__.split(".")[:2])}


def layer_name(built_for: dict) -> str:
    """A layer's folder name: the wheel tags it serves and its NumPy (``cp311-linux_x86_64-numpy2.4``);
    numba's version is in its manifest (a new numba rebuilds the same layer)."""
    implementation, version = built_for["python"].split(" ")
    short = {"cpython": "cp", "pypy": "pp"}.get(implementation, implementation)
    platform = built_for["platform"].replace("-", "_").replace(".", "_")
    return f"{short}{version.replace('.', '')}-{platform}-numpy{built_for['numpy']}"


def signature_text(argument_types: tuple) -> str:
    """The argument types as a layer names them: numba's printed types."""
    return "(" + ", ".join(str(t) for t in argument_types) + ")"


def syntax_digest(source: bytes) -> str:
    """sha256 of a module's syntax tree without its docstrings: a comment or docstring edit keeps it."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            first = node.body[0] if node.body else None
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                node.body = node.body[1:] or [ast.Pass()]
    return hashlib.sha256(ast.dump(tree).encode()).hexdigest()


@functools.lru_cache(maxsize=None)
def _module_digest(module: str, known: tuple) -> str:
    """``syntax_digest`` of a module's file; ``known`` = (its file's sha256, its syntax digest) as a
    manifest recorded them spares parsing a file that has not changed."""
    source = cache_keys.module_file(module).read_bytes()
    if known and hashlib.sha256(source).hexdigest() == known[0]:
        return known[1]
    return syntax_digest(source)


def sources_key(module: str, modules: dict) -> str:
    """The key of ``module``'s kernels: its closure's module names and their syntax digests
    (``modules``: a manifest's record of them, to skip parsing unchanged files)."""
    digest = hashlib.sha256()
    for name in cache_keys.closure(module):
        known = modules.get(name)
        digest.update(f"{name} {_module_digest(name, (known['sha256'], known['syntax']) if known else ())}\n"
                      .encode())
    return digest.hexdigest()


def _settings_changed() -> list:
    """The numba settings, of ``CODE_SETTINGS``, that this process runs with other than their defaults."""
    from numba.core import config
    return [variable for variable, (name, default) in CODE_SETTINGS.items()
            if variable in os.environ or getattr(config, name, None) != default]


@functools.lru_cache(maxsize=1)
def _layer() -> tuple:
    """(the layer this process loads from, None) or (None, why there is none)."""
    if os.environ.get(SWITCH) == "0":
        return None, f"{SWITCH}=0"
    changed = _settings_changed()
    if changed:
        return None, f"{', '.join(changed)} set: the shipped kernels are built with numba's defaults"
    here, seen = setup(), []
    for path in sorted(ROOT.glob("*/manifest.json")):
        try:
            manifest = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if manifest.get("format") != FORMAT:
            continue
        built_for = manifest["built_for"]
        if built_for == here:
            return Layer(path.parent, manifest["kernels"], manifest["modules"]), None
        seen.append(built_for)
    if not seen:
        return None, "this install ships no compiled kernels"
    built_for = seen[0]
    differs = [key for key in here if built_for.get(key) != here[key]]
    return None, (f"the shipped kernels are for {', '.join(f'{k} {built_for.get(k)}' for k in differs)}; "
                  f"this is {', '.join(f'{k} {here[k]}' for k in differs)}")


class Loader(NamedTuple):
    """What a kernel's cache (``cache_keys.keyed``) asks the layer; ``quiet`` for helpers, which compile
    as part of the kernel that calls them (that one says so)."""

    quiet: bool

    def load(self, py_func, argument_types: tuple, target_context) -> tuple:
        """(the shipped compile result of ``py_func`` for ``argument_types``, None), or (None, why not)."""
        name = f"{py_func.__module__}.{py_func.__qualname__}"
        layer, why = _layer()
        if layer is None:
            return None, why
        entry = layer.kernels.get(name)
        signature = signature_text(argument_types)
        if entry is None or signature not in entry["signatures"]:
            return None, f"no shipped kernel takes {signature}"
        if sources_key(py_func.__module__, layer.modules) != entry["key"]:
            return None, "its sources differ from those of the shipped kernel"
        cpu = next((cpu for cpu in CPUS if cpu in entry["files"] and _runs(cpu)), None)
        if cpu is None:
            return None, f"this CPU lacks the features of {', '.join(entry['files'])}"
        built = entry["files"][cpu]
        cres, why = _rebuild(layer.folder / built["file"], built["sha256"], signature, target_context)
        if cres is not None and tuple(cres.signature.args) != tuple(argument_types):
            return None, "the shipped entry has another signature"
        if cres is not None:
            LOADED[name] += 1
        return cres, why

    def compiling(self, py_func, why: str | None) -> None:
        """``py_func`` compiles (neither shipped nor in the user's cache): the first time in this
        process, one line on stderr says so and why."""
        if not self.quiet and not _SAID:
            _SAID.append(why)
            print(f"cgaskin: compiling {py_func.__module__}.{py_func.__qualname__} ({why}); compiled kernels "
                  "are cached for later runs, and `cgaskin precompile` compiles all of them ahead, on every core",
                  file=sys.stderr, flush=True)


#: the loaders of kernels (called from Python) and of helpers
FOR_KERNELS, FOR_HELPERS = Loader(quiet=False), Loader(quiet=True)
#: what ``Loader.compiling`` said in this process (it says one line at most)
_SAID: list = []


@functools.lru_cache(maxsize=None)
def _runs(cpu: str) -> bool:
    """Whether this machine's CPU has every feature that code built for ``cpu`` assumes."""
    if not CPUS[cpu]:
        return True
    try:
        import llvmlite.binding as llvm
        features = llvm.get_host_cpu_features()
    except RuntimeError:               # LLVM cannot tell on this host: only the generic code
        return False
    return all(features.get(feature, False) for feature in CPUS[cpu])


def _rebuild(path: Path, sha256: str, signature: str, target_context) -> tuple:
    """(numba's compile result from a kernel's file, None) or (None, why not)."""
    from numba.core import compiler
    try:
        data = path.read_bytes()
    except OSError as exc:
        return None, f"its shipped file cannot be read: {exc.strerror or exc}"
    if hashlib.sha256(data).hexdigest() != sha256:
        return None, f"its shipped file {path.name} is not the one the manifest lists"
    try:
        payload = pickle.loads(pickle.loads(data)[signature])
        target_context.refresh()
        return compiler.CompileResult._rebuild(target_context, *payload), None
    except Exception as exc:       # a layer this numba cannot read after all: compile (never a crash)
        return None, f"its shipped entry does not load: {type(exc).__name__}: {exc}"


