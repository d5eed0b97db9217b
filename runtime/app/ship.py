"""Build the kernels that ship compiled (``cgaskin build --kernels``) and check them (``--check``).

The layer (``cgaskin._shared.shipped`` loads it) holds every signature ``precompile`` records, compiled
for LLVM's ``generic`` x86-64 CPU (and the kernels ``jit.WIDE`` marks for x86-64-v3 too), without SVML
and with numba's default options, in builder processes whose numba is set so (``NUMBA_CPU_NAME``:
that setting changes every function of a process, so it is never set in the user's). Only the kernels whose key
changed are compiled and rewritten (numba's object code names functions by a per-process counter, so
a rebuilt kernel's file differs even when its code does not): a change rewrites the files it touches.

Each kernel's machine code holds the code of the helpers it calls (numba links them in). Its key must
cover them, so the build reads the functions linked into each kernel and fails when one comes from a
cgaskin module outside the kernel's import closure (a helper passed in as an argument, say, or
imported lazily by another module).
"""
from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import NamedTuple

from .._shared import cache_keys, shipped
from .._shared.jit import SIGNATURES
from ..errors import KernelBuildError

__all__ = ["build_kernels", "check_kernels", "escaped_modules"]

#: a builder process: compiles the kernels named as arguments for the CPU its numba is set to, writes
#: their files, prints their entries
_BUILDER = "import sys; from cgaskin.app.ship import _build_here; _build_here(sys.argv[1], sys.argv[2:])"


class Wanted(NamedTuple):
    """What the layer must hold of one kernel: its module, its argument types' texts, its CPUs."""

    module: str
    signatures: list
    cpus: tuple


def _wanted() -> dict:
    """'module.function' -> ``Wanted`` for every kernel with a recorded signature."""
    wanted = {}
    for signature in SIGNATURES:
        name = f"{signature.module}.{signature.name}"
        texts = wanted.setdefault(name, Wanted(signature.module, [], signature.targets)).signatures
        text = shipped.signature_text(tuple(signature.argtypes))
        if text not in texts:
            texts.append(text)
    return wanted


def _module_digests(wanted: dict) -> dict:
    """module -> {"sha256", "syntax"} for every module in the closure of a wanted kernel."""
    modules = {}
    for kernel in wanted.values():
        for name in cache_keys.closure(kernel.module):
            if name not in modules:
                source = cache_keys.module_file(name).read_bytes()
                modules[name] = {"sha256": hashlib.sha256(source).hexdigest(),
                                 "syntax": shipped.syntax_digest(source)}
    return dict(sorted(modules.items()))


def _read_manifest(folder: Path) -> dict | None:
    try:
        manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return manifest if manifest.get("format") == shipped.FORMAT else None


def _stale(manifest: dict | None, folder: Path, wanted: dict, keys: dict) -> list:
    """The wanted kernels that ``manifest``'s layer lacks, or holds for other sources, types or CPUs."""
    entries = manifest["kernels"] if manifest else {}
    stale = []
    for name, kernel in wanted.items():
        entry = entries.get(name)
        if entry is None or entry["key"] != keys[name] or entry["signatures"] != kernel.signatures \
                or sorted(entry["files"]) != sorted(kernel.cpus):
            stale.append(name)
        elif any(not (folder / built["file"]).is_file()
                 or hashlib.sha256((folder / built["file"]).read_bytes()).hexdigest() != built["sha256"]
                 for built in entry["files"].values()):
            stale.append(name)
    return stale


def _keys(wanted: dict) -> tuple[dict, dict]:
    """(the modules' digests, each wanted kernel's key) for the sources as they are."""
    modules = _module_digests(wanted)
    return modules, {name: shipped.sources_key(kernel.module, modules) for name, kernel in wanted.items()}


def check_kernels() -> tuple[list, list]:
    """(the stale kernels, notes): the layers of this Python and platform checked against the sources
    (a layer for another numba or NumPy is checked too: only its machine code cannot be used here)."""
    wanted = _wanted()
    _, keys = _keys(wanted)
    here = shipped.setup()
    layers = [path.parent for path in sorted(shipped.ROOT.glob("*/manifest.json"))]
    manifests = {folder: _read_manifest(folder) or {"built_for": {}, "kernels": {}} for folder in layers}
    mine = [folder for folder in layers if all(manifests[folder]["built_for"].get(key) == here[key]
                                               for key in ("python", "platform"))]
    if not mine:
        if layers:
            return [], [f"no shipped kernels for {here['python']} on {here['platform']} (the layers are "
                        f"{', '.join(folder.name for folder in layers)}): nothing to check here"]
        return sorted(wanted), [f"no shipped kernels in {shipped.ROOT}"]
    stale, notes = [], []
    for folder in mine:
        manifest = manifests[folder]
        stale += [f"{folder.name}: {name}" for name in _stale(manifest, folder, wanted, keys)]
        stale += [f"{folder.name}: {name} (no longer recorded)"
                  for name in sorted(set(manifest["kernels"]) - set(wanted))]
    usable = [folder for folder in mine if manifests[folder]["built_for"] == here]
    if not usable:              # (a layer for another NumPy, Blender's say, beside this setup's is expected)
        for folder in mine:
            built_for = manifests[folder]["built_for"]
            differs = [f"{k} {built_for[k]} (installed: {here[k]})" for k in ("numba", "llvmlite", "numpy")
                       if built_for[k] != here[k]]
            notes.append(f"{folder.name} is built for {', '.join(differs)}: its kernels compile at their first "
                         "use here")
    return stale, notes


def build_kernels(jobs: int | None = None, verbose: bool = True) -> list:
    """Compile the stale kernels of this setup's layer and write them (and the manifest); returns their
    names. Raises ``KernelBuildError`` when a kernel fails to compile or links code its key misses."""
    from .precompile import default_jobs
    wanted = _wanted()
    modules, keys = _keys(wanted)
    here = shipped.setup()
    folder = shipped.ROOT / shipped.layer_name(here)
    manifest = _read_manifest(folder)
    if manifest is not None and manifest["built_for"] != here:
        manifest = None                         # another numba: every kernel is rebuilt
    stale = _stale(manifest, folder, wanted, keys)
    old = manifest["kernels"] if manifest else {}
    if verbose:
        print(f"shipped kernels ({folder}): {len(stale)} of {len(wanted)} to build", flush=True)
    for built in [built for name, entry in old.items() if name not in wanted or name in stale
                  for built in entry["files"].values()]:
        (folder / built["file"]).unlink(missing_ok=True)
    entries = {name: old[name] for name in wanted if name not in stale}
    for cpu in shipped.CPUS:
        names = [name for name in stale if cpu in wanted[name].cpus]
        for name, built in (_compile_for(cpu, names, folder, jobs or default_jobs()) if names else {}).items():
            entries.setdefault(name, {"key": keys[name], "signatures": wanted[name].signatures, "files": {}})
            entries[name]["files"][cpu] = built
    for name, kernel in wanted.items():         # (what each depends on, for a reader of the manifest)
        entries[name]["modules"] = list(cache_keys.closure(kernel.module))
    layer = {"format": shipped.FORMAT, "built_for": here,
             "target": {"cpus": list(shipped.CPUS), "cpu_features": "", "svml": False, "options": "numba's defaults"},
             "modules": modules, "kernels": dict(sorted(entries.items()))}
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "manifest.json").write_text(json.dumps(layer, indent=1) + "\n", encoding="utf-8")
    _remove_empty_folders(folder)
    return stale


def _compile_for(cpu: str, names: list, folder: Path, jobs: int) -> dict:
    """Compile ``names`` in ``jobs`` builder processes whose numba targets ``cpu``; name -> {"file",
    "sha256"}. Each builder has an empty numba cache of its own: everything its kernels call compiles
    in it, so that the code linked into each kernel can be read (``escaped_modules``)."""
    from .precompile import KERNELS, _shares
    env = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    # (an empty feature list: a named CPU otherwise adds the host's features)
    env.update(NUMBA_CPU_NAME=cpu, NUMBA_CPU_FEATURES="", NUMBA_DISABLE_INTEL_SVML="1")
    indices = [i for i, s in enumerate(KERNELS) if f"{s.module}.{s.name}" in names]
    shares = [sorted({f"{KERNELS[i].module}.{KERNELS[i].name}" for i in share}) for share in _shares(indices, jobs)]
    with tempfile.TemporaryDirectory(prefix="cgaskin-kernels-") as caches:
        builders = [subprocess.Popen([sys.executable, "-c", _BUILDER, str(folder), *share],
                                     env={**env, "NUMBA_CACHE_DIR": str(Path(caches, str(k)))},
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)
                    for k, share in enumerate(shares)]
        reports = [builder.communicate() for builder in builders]
    failed = [error.strip() for builder, (_, error) in zip(builders, reports) if builder.returncode]
    if failed:
        raise KernelBuildError(f"building the shipped kernels for {cpu} failed:\n" + "\n".join(failed))
    built = {}
    for output, _ in reports:
        built.update(json.loads(output.strip().splitlines()[-1]))
    return built


def _build_here(folder: str, names: list) -> None:
    """In a builder process: compile these kernels, check the code linked into each, write their files
    into ``folder``, print name -> {"file", "sha256"} (JSON, one line)."""
    import importlib

    from numba.core import config
    from numba.core.registry import cpu_target
    cpu, features = cpu_target.target_context.codegen().magic_tuple()[1:]
    if cpu not in shipped.CPUS or features or config.USING_SVML:
        raise SystemExit(f"the builder's numba targets {cpu} with features {features!r} (SVML {config.USING_SVML}), "
                         f"not one of {list(shipped.CPUS)} alone")
    wanted, built = _wanted(), {}
    for name in names:
        module = wanted[name].module
        dispatcher = importlib.import_module(module).__dict__[name.rpartition(".")[2]]
        for signature in SIGNATURES:
            if f"{signature.module}.{signature.name}" == name:
                dispatcher.compile(tuple(signature.argtypes))
                escaped = escaped_modules(dispatcher.overloads[tuple(signature.argtypes)].library, module)
                if escaped:
                    raise SystemExit(f"{name} links code of {', '.join(escaped)}, which its key does not cover: "
                                     f"import what it calls at module level in {module} or in a module it imports")
        built[name] = _write_kernel(Path(folder), name, dispatcher, wanted[name].signatures, cpu)
    print(json.dumps(built))


def _write_kernel(folder: Path, name: str, dispatcher, texts: list, cpu: str) -> dict:
    """Write one kernel's file for ``cpu`` from its builder's numba cache; {"file", "sha256"}."""
    cache = dispatcher._cache.disk()                     # numba's cache of it (the builder's empty folder)
    payloads = {}
    for key, data_name in cache._cache_file._load_index().items():
        text = shipped.signature_text(cache_keys.argument_types(key[0]))
        if text in texts:
            payloads[text] = Path(cache._cache_file._data_path(data_name)).read_bytes()
    missing = [text for text in texts if text not in payloads]
    if missing:
        raise SystemExit(f"{name}: numba's cache holds no entry for {missing} (not cachable?)")
    module = dispatcher.py_func.__module__
    data = pickle.dumps({text: payloads[text] for text in texts}, protocol=4)
    relative = f"{module}/{name.rpartition('.')[2]}{'' if cpu == 'generic' else '.' + cpu}.nbk"
    (folder / module).mkdir(parents=True, exist_ok=True)
    (folder / relative).write_bytes(data)
    return {"file": relative, "sha256": hashlib.sha256(data).hexdigest()}


def escaped_modules(library, module: str) -> list:
    """The modules whose code a compiled kernel of ``module`` holds (``library``: its numba code library,
    as compiled in this process) that its key does not cover: of its own package but outside its
    import closure, or of a package other than its own and numba (whose version the layer records)."""
    top, closure = module.split(".")[0], set(cache_keys.closure(module))
    return sorted(name for name in _linked_modules(library)
                  if name not in closure and (name.split(".")[0] == top or name.split(".")[0] != "numba"))


def _linked_modules(library) -> set:
    """The Python modules of the compiled functions in ``library`` and every library numba linked into it,
    read from their mangled names (``_ZN<len><part>...``). (Once optimised, a kernel's own code no longer
    names the callees inlined into it: the libraries it links still do.)"""
    modules, stack, seen = set(), [library], set()
    while stack:
        library = stack.pop()
        if id(library) in seen:
            continue
        seen.add(id(library))
        stack.extend(library._linking_libraries)
        for llvm_module in (library._final_module, library._shared_module):
            for function in () if llvm_module is None else llvm_module.functions:
                if not function.is_declaration:
                    modules.update(_module_of(function.name))
    return modules


def _module_of(symbol: str) -> set:
    """{the module of a numba-mangled function name}, or an empty set for another symbol."""
    start = symbol.find("_ZN")
    if start < 0:
        return set()
    parts, i = [], start + 3
    while i < len(symbol) and symbol[i].isdigit():
        j = i
        while symbol[j].isdigit():
            j += 1
        parts.append(symbol[j:j + int(symbol[i:j])])
        i = j + int(symbol[i:j])
    for k in range(len(parts) - 1, 0, -1):          # the longest leading run of parts that is a module
        name = ".".join(parts[:k])
        if name in sys.modules or cache_keys.module_file(name) is not None:
            return {name}
    return set()


def _remove_empty_folders(folder: Path) -> None:
    for child in folder.iterdir():
        if child.is_dir() and not any(child.iterdir()):
            shutil.rmtree(child)
