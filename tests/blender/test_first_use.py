"""First use in Blender: the kernels ship compiled for Blender 5.0's Python 3.11 and NumPy 1.26, so the
operators find every kernel loadable and start no compile; where they did not ship (here: the layer
switched off, an empty numba cache), the add-on sees what is missing and would compile it in a
subprocess (``cgaskin_blender.kernels``) instead of freezing Blender."""
import json
import os
import subprocess
from pathlib import Path

BLENDER = Path(__file__).resolve().parents[2] / "blender"
PROBE = f"""
import json, sys, time
sys.path.insert(0, {str(BLENDER)!r})
import bpy
start = time.perf_counter()
from cgaskin_blender import kernels
from cgaskin.app.precompile import missing_kernels
from cgaskin._shared import shipped
ready = kernels.ready()
print(json.dumps({{"ready": ready, "missing": len(missing_kernels()), "loaded": sum(shipped.LOADED.values()),
                  "seconds": time.perf_counter() - start}}))
"""


def probe(blender, tmp_path, **env) -> dict:
    run = subprocess.run([blender, "-c", PROBE], capture_output=True, text=True, timeout=300,
                         env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), **env})
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_the_shipped_kernels_serve_blenders_python_and_numpy(blender, tmp_path):
    out = probe(blender, tmp_path)
    assert out["ready"] and out["missing"] == 0 and out["loaded"] > 50
    assert out["seconds"] < 30, out


def test_without_them_the_add_on_sees_what_would_compile(blender, tmp_path):
    out = probe(blender, tmp_path, CGASKIN_SHIPPED_KERNELS="0")
    assert not out["ready"] and out["missing"] > 50 and out["loaded"] == 0
