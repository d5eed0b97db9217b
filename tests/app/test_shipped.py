"""The kernels that ship compiled (``cgaskin/_kernels``): a first tear and the demo load them and compile
nothing; what does not match (another numba, an edited source, a damaged file, other settings)
compiles as before, correct, saying so once; a user's own numba functions compile as without cgaskin.

Each case runs in a fresh interpreter with an empty ``NUMBA_CACHE_DIR``, counting compiles with numba's
event API and loads with the layer's own counter. They need a layer built for the numba, NumPy and
Python installed: elsewhere they skip, naming the versions that differ (``cgaskin build --kernels``
builds one for them).
"""
from __future__ import annotations

import hashlib
import json
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from cgaskin._shared import shipped
from cgaskin.app import ship
from tests.helpers.compile_events import RECORD_COMPILES

REPO = Path(__file__).resolve().parents[2]
NO_JIT = os.environ.get("NUMBA_DISABLE_JIT") == "1"

# a fresh interpreter: record what numba compiles, run WORK, print what compiled and loaded
PROBE = textwrap.dedent("""\
    import hashlib, json, sys, time
    from pathlib import Path
    start = time.perf_counter()
""") + RECORD_COMPILES + textwrap.dedent("""\
    import numpy as np
    import cgaskin
    from cgaskin._shared import shipped
    if len(sys.argv) > 2:
        shipped.ROOT = Path(sys.argv[2])                # another layer (a doctored copy)
    digest = lambda *arrays: hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)).hexdigest()
    out = None
    exec(sys.argv[1])
    print(json.dumps({"compiled": sorted(set(compiled)), "loaded": sorted(shipped.LOADED), "out": out,
                      "file": cgaskin.__file__, "seconds": time.perf_counter() - start}))
""")
TEAR = textwrap.dedent("""\
    cap = cgaskin.capsule_arm()
    blade = lambda x, y: ([x, y, 1.0], [x, y, 0.0])
    torn = cgaskin.tear(cap, blade(1.0, 0.05), blade(1.5, 0.05), opening=0.2)
    out = digest(torn.vertices, torn.faces, torn.weights)
""")
SKIN = textwrap.dedent("""\
    rig = cgaskin.capsule_arm()
    pose = rig.rest_pose().rotate(1, [0, 0, 1], 0.4).dilate(2, 1.3)
    out = digest(cgaskin.skin(rig, pose))
""")


def _usable_layer():
    """Skip unless a shipped layer matches the installed versions (then these tests can run)."""
    if NO_JIT:
        pytest.skip("NUMBA_DISABLE_JIT=1: nothing is compiled or loaded")
    layer, why = shipped._layer()
    if layer is None:
        pytest.skip(f"no shipped kernels for this setup: {why}")
    return layer


def run(work: str, cache: Path, layer: Path | None = None, python: str = sys.executable, env: dict | None = None,
        cwd: Path | None = None) -> tuple[dict, str]:
    """(what the probe printed, its stderr) for ``work`` in a fresh interpreter with the numba cache
    ``cache`` (created empty if missing)."""
    cache.mkdir(parents=True, exist_ok=True)
    environment = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    environment.update(env or {})
    environment.setdefault("NUMBA_CACHE_DIR", str(cache))
    done = subprocess.run([python, "-c", PROBE, work] + ([str(layer)] if layer else []), capture_output=True,
                          text=True, env=environment, cwd=cwd or REPO, timeout=900)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def cache_files(cache: Path) -> list:
    return sorted(str(p.relative_to(cache)) for p in cache.rglob("*") if p.is_file())


def copy_of_cgaskin(root: Path) -> Path:
    """The package's sources with its shipped kernels under ``root/src/cgaskin``; returns ``root/src``
    (put it first on PYTHONPATH: it comes before the editable install's finder)."""
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    package = root / "src" / "cgaskin"
    shutil.copytree(REPO / "runtime", package, ignore=ignore)
    for part in ("generated", "rigs", "codegen"):
        shutil.copytree(REPO / part, package / part, ignore=ignore)
    return root / "src"


def test_a_first_tear_and_the_demo_load_every_kernel_and_compile_nothing(tmp_path):
    _usable_layer()
    result, stderr = run(TEAR, tmp_path / "tear")
    assert result["compiled"] == [] and result["loaded"], stderr
    assert "cgaskin: compiling" not in stderr
    demo = f"from cgaskin.app.cli import main\nassert main(['demo', '--out', {str(tmp_path / 'demo')!r}]) == 0"
    result, stderr = run(demo, tmp_path / "demo-cache")
    assert result["compiled"] == [] and len(result["loaded"]) > 20, stderr
    assert sorted(p.name for p in (tmp_path / "demo").iterdir()) == sorted(
        ["deform.png", "capsule_arm.glb", "cut.png", "cut_upper.glb", "cut_lower.glb", "tear.png", "torn.glb",
         "drill.png", "drilled.glb"])
    # nothing was compiled, so nothing was written to the user's cache
    assert cache_files(tmp_path / "tear") == [] and cache_files(tmp_path / "demo-cache") == []


def test_shipped_and_compiled_kernels_give_the_same_results(tmp_path):
    """The same bits (no fused multiply-add on one side only); benchmarks/bench_shipped.py compares a
    cut, a tear stroke and a drill too."""
    _usable_layer()
    shipped_run, _ = run(SKIN, tmp_path / "shipped")
    compiled_run, stderr = run(SKIN, tmp_path / "compiled", env={shipped.SWITCH: "0"})
    assert shipped_run["loaded"] and not shipped_run["compiled"]
    assert not compiled_run["loaded"] and compiled_run["compiled"]
    assert f"({shipped.SWITCH}=0)" in stderr
    assert shipped_run["out"] == compiled_run["out"]


USER = textwrap.dedent("""\
    import re, sys
    import numpy as np
    from numba import njit
    from numba.core.registry import cpu_target
    if sys.argv[1] == "after cgaskin":
        import cgaskin
        from cgaskin._shared import shipped
        cap = cgaskin.capsule_arm()
        cgaskin.tear(cap, ([1.0, 0.05, 1.0], [1.0, 0.05, 0.0]), ([1.5, 0.05, 1.0], [1.5, 0.05, 0.0]))
        assert shipped.LOADED

    @njit
    def norm2(a):
        s = 0.0
        for x in a:
            s += x * x
        return s

    assert norm2(np.arange(4.0)) == 14.0
    print(cpu_target.target_context.codegen().magic_tuple())
    # the machine code, its symbols' per-process numbering aside
    print(re.sub(r"\\S*_ZN\\w+", "SYMBOL", norm2.inspect_asm(norm2.signatures[0])))
""")


def test_a_users_function_compiles_as_without_cgaskin(tmp_path):
    _usable_layer()
    env = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    env["NUMBA_CACHE_DIR"] = str(tmp_path)
    outputs = [subprocess.run([sys.executable, "-c", USER, when], capture_output=True, text=True, env=env,
                              timeout=300) for when in ("alone", "after cgaskin")]
    for done in outputs:
        assert done.returncode == 0, done.stderr
    alone, after = (done.stdout for done in outputs)
    assert "generic" not in alone.splitlines()[0]           # the host's CPU, features and all
    assert after == alone


@pytest.mark.parametrize("doctor, why", [
    ("corrupt", "its shipped file skin_blend"),
    ("numba", "the shipped kernels are for numba 0.0.1; this is numba "),
    ("opt", "NUMBA_OPT set: the shipped kernels are built with numba's defaults"),
])
def test_what_does_not_match_compiles_correctly_and_says_so_once(tmp_path, doctor, why):
    layer = _usable_layer()
    reference, _ = run(SKIN, tmp_path / "reference")
    copy = tmp_path / "layers" / layer.folder.name
    shutil.copytree(layer.folder, copy)
    env = {}
    if doctor == "corrupt":                                 # the file this machine would load
        files = layer.kernels["cgaskin.generated.skinning.skin_blend"]["files"]
        path = copy / files[next(cpu for cpu in shipped.CPUS if cpu in files and shipped._runs(cpu))]["file"]
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 0xFF
        path.write_bytes(bytes(data))
    elif doctor == "numba":
        manifest = json.loads((copy / "manifest.json").read_text())
        manifest["built_for"]["numba"] = "0.0.1"
        (copy / "manifest.json").write_text(json.dumps(manifest))
    else:
        env["NUMBA_OPT"] = "3"
    result, stderr = run(SKIN, tmp_path / "cache", layer=copy.parent, env=env)
    assert result["out"] == reference["out"]
    assert "cgaskin.generated.skinning.skin_blend" in result["compiled"]
    lines = [line for line in stderr.splitlines() if line.startswith("cgaskin: compiling")]
    assert len(lines) == 1 and why in lines[0], stderr
    assert cache_files(tmp_path / "cache")                  # what compiled is cached as before


def test_a_loaded_entry_of_another_signature_is_not_used(tmp_path, monkeypatch):
    """Two processes writing numba's cache at once can file an entry under another signature: the layer
    checks every entry it loads against the signature asked for."""
    layer = _usable_layer()
    name = "cgaskin.surgery.cut.assemble._assemble"       # a kernel shipped for two argument types
    entry = layer.kernels[name]
    first, second = entry["signatures"]
    copy = tmp_path / layer.folder.name
    shutil.copytree(layer.folder, copy)
    path = copy / entry["files"]["generic"]["file"]
    payloads = pickle.loads(path.read_bytes())
    path.write_bytes(pickle.dumps({first: payloads[second], second: payloads[first]}, protocol=4))
    manifest = json.loads((copy / "manifest.json").read_text())
    manifest["kernels"][name]["files"]["generic"]["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (copy / "manifest.json").write_text(json.dumps(manifest))
    monkeypatch.setattr(shipped, "ROOT", tmp_path)
    shipped._layer.cache_clear()
    try:
        from cgaskin.surgery.cut import assemble
        from numba.core import sigutils
        from numba.core.registry import cpu_target
        dispatcher = assemble._assemble
        argtypes = next(tuple(s.argtypes) for s in ship.SIGNATURES if s.name == "_assemble"
                        and shipped.signature_text(tuple(s.argtypes)) == first)
        cres, why = shipped.FOR_KERNELS.load(dispatcher.py_func, argtypes, cpu_target.target_context)
        assert cres is None and why == "the shipped entry has another signature"
        # the untouched layer loads it
        monkeypatch.undo()
        shipped._layer.cache_clear()
        cres, why = shipped.FOR_KERNELS.load(dispatcher.py_func, argtypes, cpu_target.target_context)
        assert cres is not None and tuple(sigutils.normalize_signature(cres.signature)[0]) == argtypes
    finally:
        monkeypatch.undo()
        shipped._layer.cache_clear()


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def test_an_edit_compiles_exactly_the_kernels_that_depend_on_it(tmp_path):
    """A comment or docstring edit compiles nothing; a code edit compiles the kernels whose manifest
    entry lists the edited module (and loads the rest); an edited constant in a helper module that a
    kernel compiles in changes the output; ``cgaskin build --kernels --check`` lists them."""
    layer = _usable_layer()
    src = copy_of_cgaskin(tmp_path)
    env = {"PYTHONPATH": str(src)}
    walk = src / "cgaskin" / "surgery" / "tear" / "walk.py"
    before, _ = run(TEAR, tmp_path / "before", env=env)
    assert before["file"] == str(src / "cgaskin" / "__init__.py") and not before["compiled"]

    _edit(walk, '"""', '"""An edited docstring. ')
    walk.write_text(walk.read_text(encoding="utf-8") + "\n# an edited comment\n", encoding="utf-8")
    commented, _ = run(TEAR, tmp_path / "commented", env=env)
    assert commented["compiled"] == [] and commented["loaded"] == before["loaded"]

    # a code edit in walk.py, and a constant the opening of a slit compiles in (tear/opening.py)
    walk.write_text(walk.read_text(encoding="utf-8") + "\nEDITED = 1\n", encoding="utf-8")
    _edit(src / "cgaskin" / "surgery" / "tear" / "opening.py", "OPENING_SHARE = 0.5", "OPENING_SHARE = 0.05")
    edited, stderr = run(TEAR, tmp_path / "edited", env=env)
    depends = {name for name, entry in layer.kernels.items()
               if {"cgaskin.surgery.tear.walk", "cgaskin.surgery.tear.opening"} & set(entry["modules"])}
    used = set(before["loaded"])                          # (a fused kernel's callees are compiled into it)
    assert used & depends and used - depends
    compiled = set(edited["compiled"]) & set(layer.kernels)
    assert used & depends <= compiled <= depends, compiled
    # the rest loads (and the callees the recompiled kernels call: they are not compiled again)
    assert used - depends <= set(edited["loaded"]) and not set(edited["loaded"]) & depends
    assert "its sources differ from those of the shipped kernel" in stderr
    assert edited["out"] != before["out"]                 # the new constant is in the compiled code

    done = subprocess.run([sys.executable, "-m", "cgaskin", "build", "--kernels", "--check"], capture_output=True,
                          text=True, env={**os.environ, **env}, cwd=tmp_path, timeout=300)
    assert done.returncode == 1, done.stdout + done.stderr
    listed = {line.split(": ")[1] for line in done.stdout.splitlines() if line.startswith(f"  {layer.folder.name}: ")}
    assert listed == depends and "cgaskin build --kernels" in done.stdout


def test_no_writable_cache_folder(tmp_path):
    """Where no folder can hold numba's cache (read-only package, no NUMBA_CACHE_DIR, no user cache
    folder), import works, the shipped kernels load, and what must compile compiles in memory."""
    _usable_layer()
    src = copy_of_cgaskin(tmp_path)
    for folder in [src / "cgaskin", *(p for p in (src / "cgaskin").rglob("*") if p.is_dir())]:
        (folder / "__pycache__").write_text("a file, where numba would make its cache folder")
    blocked = tmp_path / "not-a-folder"
    blocked.write_text("")
    env = {"PYTHONPATH": str(src), "PYTHONDONTWRITEBYTECODE": "1", "XDG_CACHE_HOME": str(blocked / "cache"),
           "NUMBA_CACHE_DIR": ""}
    unrecorded = textwrap.dedent("""\
        from cgaskin.generated import kernels
        versors = np.zeros((6, 12))[::2]; versors[:, 0] = 1.0
        reversed_ = np.empty((3, 12))
        kernels.reverse_versor_batch(versors, reversed_)     # strided: no shipped kernel takes it
        assert kernels.reverse_versor_batch._cache.cache_path is None and (reversed_ == versors).all()
    """)
    result, stderr = run(TEAR + unrecorded, tmp_path / "unused", env=env)
    assert result["loaded"], stderr
    assert result["compiled"] == ["cgaskin.generated.kernels.reverse_versor",       # (the row kernel it calls)
                                  "cgaskin.generated.kernels.reverse_versor_batch"], stderr
    assert "no shipped kernel takes (array(float64, 2d, A), array(float64, 2d, C))" in stderr


def test_the_build_refuses_a_kernel_that_links_code_its_key_misses(tmp_path):
    """A helper passed to a kernel as an argument is compiled into it, but its module is not among
    those the kernel's module imports: the build names it."""
    if NO_JIT:
        pytest.skip("NUMBA_DISABLE_JIT=1: nothing is compiled")
    package = tmp_path / "probe_pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "shift.py").write_text("from cgaskin._shared.jit import helper\n\n\n@helper\ndef shift(x):\n"
                                      "    return x + 1.0\n")
    (package / "apply.py").write_text("from cgaskin._shared.jit import kernel\n\n\n@kernel()\ndef apply(f, x):\n"
                                      "    return f(x)\n\n\n@kernel()\ndef twice(x):\n    return 2.0 * x\n")
    (package / "direct.py").write_text("from cgaskin._shared.jit import kernel\n\nfrom .shift import shift\n\n\n"
                                       "@kernel()\ndef shifted(x):\n    return shift(x)\n")
    script = textwrap.dedent("""\
        import sys
        sys.path.insert(0, sys.argv[1])
        from cgaskin.app.ship import escaped_modules
        from probe_pkg import apply, direct, shift
        assert apply.apply(shift.shift, 1.0) == 2.0 and direct.shifted(1.0) == 2.0 and apply.twice(1.0) == 2.0
        for function, module in ((apply.apply, "probe_pkg.apply"), (apply.twice, "probe_pkg.apply"),
                                 (direct.shifted, "probe_pkg.direct")):
            (compiled,) = function.overloads.values()
            print(escaped_modules(compiled.library, module))
    """)
    env = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "cache")
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path)], capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:3] == ["['probe_pkg.shift']", "[]", "[]"]


def test_the_shipped_kernels_are_fresh():
    """The repository's layer matches its sources (``cgaskin build --check`` says the same in CI)."""
    if shipped.setup()["python"] != "cpython 3.11":
        pytest.skip(f"the layer is built for CPython 3.11; this is {shipped.setup()['python']}")
    stale, notes = ship.check_kernels()
    assert stale == [], f"stale shipped kernels: rebuild them with `cgaskin build --kernels`: {stale}"


def test_a_wheel_carries_the_kernels_and_its_first_tear_compiles_nothing(tmp_path):
    """``python -m build`` makes a wheel tagged for the layer's Python and platform; installed in a
    fresh virtual environment (numba and NumPy from this one), its first tear loads and compiles
    nothing. (About 15 s: the wheel's build, the environment, the install.)"""
    layer = _usable_layer()
    pytest.importorskip("build", reason="the test extra's `build` makes the wheel")
    done = subprocess.run([sys.executable, "-m", "build", "--wheel", "--outdir", str(tmp_path / "dist"), str(REPO)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (wheel,) = (tmp_path / "dist").glob("*.whl")
    python_tag, platform = layer.folder.name.split("-")[:2]
    assert wheel.name.endswith(f"-{python_tag}-{python_tag}-{platform}.whl"), wheel.name
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True, timeout=300)
    python = str(venv / "bin" / "python")
    subprocess.run([python, "-m", "pip", "install", "-q", "--no-deps", str(wheel)], check=True, timeout=300)
    result, stderr = run(TEAR, tmp_path / "cache", python=python, cwd=tmp_path)
    assert result["file"].startswith(str(venv)), result["file"]
    assert result["compiled"] == [] and result["loaded"], stderr


def test_a_kernel_loads_for_the_best_cpu_this_machine_runs(monkeypatch):
    """Skinning's blend ships for x86-64-v3 too: it loads that where the CPU has AVX2 and FMA and the
    rest of that level, else the generic code (never code this CPU cannot run)."""
    layer = _usable_layer()
    from numba.core.registry import cpu_target

    from cgaskin.generated import skinning
    assert sorted(layer.kernels["cgaskin.generated.skinning.skin_blend"]["files"]) == ["generic", "x86-64-v3"]
    assert shipped._runs("generic")
    argtypes = next(tuple(s.argtypes) for s in ship.SIGNATURES if s.name == "skin_blend")
    for runs_v3 in (True, False):
        read = []
        rebuild = shipped._rebuild
        monkeypatch.setattr(shipped, "_runs", lambda cpu: runs_v3 or cpu == "generic")
        monkeypatch.setattr(shipped, "_rebuild", lambda path, *rest: read.append(path.name) or rebuild(path, *rest))
        cres, why = shipped.FOR_KERNELS.load(skinning.skin_blend.py_func, argtypes, cpu_target.target_context)
        assert cres is not None, why
        assert read == ["skin_blend.x86-64-v3.nbk" if runs_v3 else "skin_blend.nbk"]
        monkeypatch.undo()
