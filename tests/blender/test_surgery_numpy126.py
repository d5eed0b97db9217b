"""The surgery tests again under Blender's NumPy 1.26 (issue 45): the bpy venv's Python runs
``pytest tests/surgery`` (all but ``LEFT_OUT``) in a subprocess (this suite's NumPy is 2.x; one
environment cannot hold both), from the NumPy 1.26 layer of shipped kernels. What the layer lacks (the
tests' own kernels, signatures that only tests call) compiles into a numba cache of its own that stays
between runs: numba does not key its cache entries by NumPy's version, so entries compiled under NumPy 2
must not stand in. Measured on 2 cores: 87 s with that cache warm, 99 s cold (a fresh machine)."""
import os
import subprocess
from pathlib import Path

from tests.clients.conftest import SUMMARY

REPO = Path(__file__).resolve().parents[2]

#: what the venv must run: Blender 5.0's NumPy, and a layer that loads for it (else every kernel compiles,
#: minutes; the message says how to build it)
PROBE = ("import numpy; from cgaskin._shared import shipped; layer, why = shipped._layer(); "
         "print(numpy.__version__); print(layer.folder.name if layer else why)")
#: left out under NumPy 1.26 (they run under NumPy 2 with the rest of the suite): the random tears and
#: cuts repeat, with hypothesis's examples, kernels the other tests run, and test_tear_internal calls
#: internal helpers with signatures no shipped kernel has; together they cost a fresh machine about a
#: minute of compiling (measured: 99 s cold without them, 145-169 s with them)
LEFT_OUT = ("test_tear_random.py", "test_cut_random.py", "test_tear_internal.py")
#: the numba cache of the kernels compiled under NumPy 1.26 (CGASKIN_NUMPY126_CACHE moves it)
CACHE = Path(os.environ.get("CGASKIN_NUMPY126_CACHE", Path.home() / ".cache" / "cgaskin" / "numba-numpy1.26"))


def test_the_surgery_tests_pass_under_numpy_1_26(blender):
    environment = {key: value for key, value in os.environ.items()
                   if not key.startswith(("NUMBA_", "CGASKIN_SHIPPED", "PYTEST_"))}
    environment["NUMBA_CACHE_DIR"] = str(CACHE)
    probe = subprocess.run([blender, "-c", PROBE], capture_output=True, text=True, env=environment, cwd=REPO,
                           timeout=120)
    assert probe.returncode == 0, probe.stderr[-3000:]
    numpy_version, layer = probe.stdout.split("\n")[:2]
    assert numpy_version.startswith("1.26."), f"the bpy venv runs NumPy {numpy_version}, Blender 5.0's is 1.26"
    assert layer.endswith("-numpy1.26"), (
        f"no shipped kernels load under NumPy 1.26 ({layer}): build them with the bpy venv's Python, "
        f"`{blender} -m cgaskin build --kernels`")
    deselected = [f"--deselect=tests/surgery/{name}" for name in LEFT_OUT]
    done = subprocess.run([blender, "-m", "pytest", "tests/surgery", "-q", "-p", "no:cacheprovider", *deselected],
                          capture_output=True, text=True, env=environment, cwd=REPO, timeout=900)
    assert done.returncode == 0, done.stdout[-6000:] + done.stderr[-3000:]
    SUMMARY.append(f"tests/surgery under NumPy {numpy_version}: {done.stdout.strip().splitlines()[-1]}")
