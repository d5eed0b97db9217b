"""Build the kernels that ship compiled (``cgaskin build --kernels``) and check them (``--check``).

The layer (``cgaskin._shared.shipped`` loads it) holds every signature ``precompile`` records, compiled
for LLVM's ``generic`` x86-64 CPU, without SVML and with numba's default options, by ``precompile``'s
parallel compile run in processes whose numba is set so (``NUMBA_CPU_NAME=generic``: that setting
changes every function of a process, so it is never set in the user's). Only the kernels whose key
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

from .._shared import cache_keys, shipped
from .._shared.jit import SIGNATURES

__all__ = ["build_kernels", "check_kernels", "escaped_modules", "StaleKernels"]

#: the builder process: compiles the kernels named on stdin for the generic CPU, prints their records
_BUILDER = "import sys; from cgaskin.app.ship import _build_here; _build_here(sys.argv[1], int(sys.argv[2]))"


class StaleKernels(RuntimeError):
    """The shipped kernels cannot be built: a kernel links code its key does not cover, or fails."""


def _wanted() -> dict:
    """'module.function' -> (its module, [its argument types' texts]) for every recorded signature."""
    wanted = {}
    for signature in SIGNATURES:
        name = f"{signature.module}.{signature.name}"
        texts = wanted.setdefault(name, (signature.module, []))[1]
        text = shipped.signature_text(tuple(signature.argtypes))
        if text not in texts:
            texts.append(text)
    return wanted


def _module_digests(wanted: dict) -> dict:
    """module -> {"sha256", "syntax"} for every module in the closure of a wanted kernel."""
    modules = {}
    for module, _ in wanted.values():
        for name in cache_keys.closure(module):
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
    """The wanted kernels that ``manifest``'s layer lacks or holds for other sources or types."""
    entries = manifest["kernels"] if manifest else {}
    stale = []
    for name, (_, texts) in wanted.items():
        entry = entries.get(name)
        if entry is None or entry["key"] != keys[name] or entry["signatures"] != texts:
            stale.append(name)
            continue
        path = folder / entry["file"]
        if not path.is_file() or hashlib.sha256(path.read_bytes()).hexdigest() != entry["sha256"]:
            stale.append(name)
    return stale


def check_kernels() -> tuple[list, list]:
    """(the stale kernels, notes): the layers of this Python and platform checked against the sources
    (a layer for another numba or NumPy is checked too: only its machine code cannot be used here)."""
    wanted = _wanted()
    modules = _module_digests(wanted)
    keys = {name: shipped.sources_key(module, modules) for name, (module, _) in wanted.items()}
    here = shipped.setup()
    layers = [path.parent for path in sorted(shipped.ROOT.glob("*/manifest.json"))]
    mine = [folder for folder in layers
            if {k: v for k, v in (_read_manifest(folder) or {}).get("built_for", {}).items()
                if k in ("python", "platform")} == {"python": here["python"], "platform": here["platform"]}]
    if not mine:
        if layers:
            return [], [f"no shipped kernels for {here['python']} on {here['platform']} (the layers are "
                        f"{', '.join(folder.name for folder in layers)}): nothing to check here"]
        return sorted(wanted), [f"no shipped kernels in {shipped.ROOT}"]
    stale, notes = [], []
    for folder in mine:
        manifest = _read_manifest(folder)
        stale += [f"{folder.name}: {name}" for name in _stale(manifest, folder, wanted, keys)]
        stale += [f"{folder.name}: {name} (no longer recorded)" for name in sorted(set(manifest["kernels"]) - set(wanted))]
        differs = [f"{k} {manifest['built_for'][k]} (installed: {here[k]})" for k in ("numba", "llvmlite", "numpy")
                   if manifest["built_for"][k] != here[k]]
        if differs:
            notes.append(f"{folder.name} is built for {', '.join(differs)}: its kernels compile at their first "
                         "use here")
    return stale, notes


def build_kernels(jobs: int | None = None, verbose: bool = True) -> list:
    """Compile the stale kernels of this setup's layer and write them (and the manifest); returns their
    names. Raises ``StaleKernels`` when a kernel fails to compile or links code its key misses."""
    from .precompile import default_jobs
    wanted = _wanted()
    modules = _module_digests(wanted)
    keys = {name: shipped.sources_key(module, modules) for name, (module, _) in wanted.items()}
    here = shipped.setup()
    folder = shipped.ROOT / shipped.layer_name(here)
    manifest = _read_manifest(folder)
    if manifest is not None and manifest["built_for"] != here:
        manifest = None                         # another numba: every kernel is rebuilt
    stale = _stale(manifest, folder, wanted, keys)
    removed = sorted(set(manifest["kernels"]) - set(wanted)) if manifest else []
    entries = {name: entry for name, entry in (manifest["kernels"] if manifest else {}).items() if name in wanted}
    if verbose:
        print(f"shipped kernels ({folder}): {len(stale)} of {len(wanted)} to build", flush=True)
    if stale:
        entries.update(_compile_generic(stale, folder, jobs or default_jobs()))
    for name in removed:
        (folder / manifest["kernels"][name]["file"]).unlink(missing_ok=True)
    for name in stale:
        entries[name]["key"] = keys[name]
    for name, (module, _) in wanted.items():     # (what each depends on, for a reader of the manifest)
        entries[name]["modules"] = list(cache_keys.closure(module))
    layer = {"format": shipped.FORMAT, "built_for": here,
             "target": {"cpu_name": "generic", "cpu_features": "", "svml": False, "options": "numba's defaults"},
             "modules": modules, "kernels": dict(sorted(entries.items()))}
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "manifest.json").write_text(json.dumps(layer, indent=1) + "\n", encoding="utf-8")
    _remove_empty_folders(folder)
    return stale


def _compile_generic(names: list, folder: Path, jobs: int) -> dict:
    """Compile ``names`` in a builder process set for the generic CPU (and its workers); their entries."""
    env = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    with tempfile.TemporaryDirectory(prefix="cgaskin-kernels-") as cache:
        env.update(NUMBA_CPU_NAME="generic", NUMBA_DISABLE_INTEL_SVML="1", NUMBA_CACHE_DIR=cache)
        done = subprocess.run([sys.executable, "-c", _BUILDER, str(folder), str(jobs)], input="\n".join(names),
                              capture_output=True, text=True, env=env)
    if done.returncode:
        raise StaleKernels(f"building the shipped kernels failed:\n{done.stderr.strip()}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _build_here(folder: str, jobs: int) -> None:
    """In the builder process: compile the kernels named on stdin, write their files into ``folder``,
    print their manifest entries (JSON, one line)."""
    from numba.core import config
    from numba.core.registry import cpu_target
    from .precompile import KERNELS, compile_in_parallel
    magic = cpu_target.target_context.codegen().magic_tuple()
    if magic[1:] != ("generic", "") or config.USING_SVML:
        raise SystemExit(f"the builder's numba targets {magic[1:]} (SVML {config.USING_SVML}), not the generic CPU")
    names = set(sys.stdin.read().split())
    indices = [i for i, s in enumerate(KERNELS) if f"{s.module}.{s.name}" in names]
    failed = compile_in_parallel(indices, jobs)
    if failed:
        raise SystemExit("kernels that did not compile:\n" + "\n".join(failed))
    entries = {}
    for name, (module, texts) in _wanted().items():
        if name in names:
            entries[name] = _write_kernel(Path(folder), name, module, texts)
    print(json.dumps(entries))


def _write_kernel(folder: Path, name: str, module: str, texts: list) -> dict:
    """Write one kernel's file from the builder's numba cache; its manifest entry (without its key)."""
    import importlib
    function = importlib.import_module(module).__dict__[name.rpartition(".")[2]]
    cache = function._cache.disk()                       # numba's cache of it (the builder's empty folder)
    index = cache._cache_file._load_index()
    payloads = {}
    for key, data_name in index.items():
        text = shipped.signature_text(cache_keys.argument_types(key[0]))
        if text in texts:
            payloads[text] = Path(cache._cache_file._data_path(data_name)).read_bytes()
    missing = [text for text in texts if text not in payloads]
    if missing:
        raise SystemExit(f"{name}: numba's cache holds no entry for {missing} (not cachable?)")
    for text, raw in payloads.items():
        escaped = escaped_modules(raw, module)
        if escaped:
            raise SystemExit(f"{name} {text} links code of {', '.join(escaped)}, which its key does not cover: "
                             f"import what it calls at module level in {module} or in a module it imports")
    data = pickle.dumps({text: payloads[text] for text in texts}, protocol=4)
    relative = f"{module}/{name.rpartition('.')[2]}.nbk"
    (folder / module).mkdir(parents=True, exist_ok=True)
    (folder / relative).write_bytes(data)
    return {"file": relative, "sha256": hashlib.sha256(data).hexdigest(), "signatures": texts}


def escaped_modules(raw: bytes, module: str) -> list:
    """The modules whose code a kernel of ``module`` links (``raw``: its entry in numba's cache) that its
    key does not cover: of its own package but outside its import closure, or of a package other than
    its own and numba (whose version the layer records)."""
    top, closure = module.split(".")[0], set(cache_keys.closure(module))
    return sorted(name for name in _linked_modules(raw)
                  if name not in closure and (name.split(".")[0] == top or name.split(".")[0] != "numba"))


def _linked_modules(raw: bytes) -> set:
    """The Python modules whose compiled functions a cached kernel's code defines (its own and every
    callee numba linked in), read from the mangled names (``_ZN<len><part>...``) of its bitcode."""
    import llvmlite.binding as llvm
    library = pickle.loads(raw)[0]                       # numba's (name, "object", (object code, bitcode))
    modules = set()
    for function in llvm.parse_bitcode(library[2][1]).functions:
        start = function.name.find("_ZN")
        if function.is_declaration or start < 0:
            continue
        parts, name, i = [], function.name, start + 3
        while i < len(name) and name[i].isdigit():
            j = i
            while name[j].isdigit():
                j += 1
            parts.append(name[j:j + int(name[i:j])])
            i = j + int(name[i:j])
        for k in range(len(parts) - 1, 0, -1):          # the longest leading run of parts that is a module
            if cache_keys.module_file(".".join(parts[:k])) is not None or ".".join(parts[:k]) in sys.modules:
                modules.add(".".join(parts[:k]))
                break
    return modules


def _remove_empty_folders(folder: Path) -> None:
    for child in folder.iterdir():
        if child.is_dir() and not any(child.iterdir()):
            shutil.rmtree(child)
