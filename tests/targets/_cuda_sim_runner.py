"""Runs numba-cuda kernels under the CUDA simulator in a process of its own.

    NUMBA_ENABLE_CUDASIM=1 python tests/targets/_cuda_sim_runner.py

The simulator must be chosen before numba is first imported, and a pytest session has imported numba
long before (the runtime's kernels), so tests/targets/test_cuda.py starts this script once per module
and talks to it over its stdin/stdout: each message is an 8-byte little-endian length and a pickle.
A request is (path of a rendered ``<prefix>_cuda.py``, name of a ``@cuda.jit`` kernel in it, blocks,
threads, [arguments]); the runner launches ``kernel[blocks, threads](*arguments)`` and answers ("ok",
[arguments as they are afterwards]) or ("error", traceback text). It prints ``ready`` first.

Where the simulator is not the device. The simulator runs device functions as Python: ``math.sqrt(-1)``,
``math.log(0)`` and ``x / 0.0`` on Python floats raise, where the GPU (IEEE 754, like numba on the CPU)
gives NaN or infinity; and its ``cuda.cbrt`` is ``a ** (1/3)`` (NaN for a < 0), where the device calls
libdevice's ``__nv_cbrt``, a cube root with the sign of ``a``. So the runner gives each rendered module an
IEEE ``math`` (math's own value wherever it has one, as an ``np.float64`` so that a later division by
zero follows IEEE too; numpy's NaN/infinity where math raises) and the simulator ``np.cbrt``. The
kernels' code is executed as rendered; only these two simulator departures from the device are undone.
"""
import importlib.util
import math
import os
import pickle
import sys
import traceback
import types

import numpy as np

MODULES = {}


def _ieee(name: str, fallback):
    def function(*args):
        try:
            return np.float64(getattr(math, name)(*args))
        except (ValueError, OverflowError, ZeroDivisionError):
            with np.errstate(all="ignore"):
                return np.float64(fallback(*(np.float64(a) for a in args)))
    function.__name__ = name
    return function


IEEE_MATH = types.SimpleNamespace(**{
    **{name: getattr(math, name) for name in dir(math) if not name.startswith("_")},
    **{name: _ieee(name, fallback) for name, fallback in (
        ("sqrt", np.sqrt), ("sin", np.sin), ("cos", np.cos), ("exp", np.exp), ("log", np.log),
        ("atan2", np.arctan2), ("acos", np.arccos), ("atanh", np.arctanh), ("cosh", np.cosh),
        ("sinh", np.sinh))}})


def _device_cbrt(self, a):
    return np.cbrt(np.float64(a))


def load(path: str):
    if path not in MODULES:
        spec = importlib.util.spec_from_file_location(f"cuda_sim_{len(MODULES)}", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.math = IEEE_MATH
        MODULES[path] = module
    return MODULES[path]


def read_message(stream):
    head = stream.read(8)
    if len(head) < 8:
        return None
    return pickle.loads(stream.read(int.from_bytes(head, "little")))


def write_message(stream, value) -> None:
    data = pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(len(data).to_bytes(8, "little") + data)
    stream.flush()


def serve(request):
    path, kernel, blocks, threads, args = request
    args = [np.float64(a) if np.ndim(a) == 0 else np.array(a) for a in args]
    getattr(load(path), kernel)[blocks, threads](*args)
    return args


def main() -> None:
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        sys.exit("_cuda_sim_runner.py needs NUMBA_ENABLE_CUDASIM=1 in its environment (before numba is imported)")
    from numba import config
    from numba.cuda.simulator.kernelapi import FakeCUDAModule
    assert config.ENABLE_CUDASIM, "numba did not enable the CUDA simulator"
    FakeCUDAModule.cbrt = _device_cbrt
    # answers go to the real stdout; anything the kernels or numba print goes to stderr
    answers = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    answers.write(b"ready\n")
    answers.flush()
    while (request := read_message(sys.stdin.buffer)) is not None:
        try:
            write_message(answers, ("ok", serve(request)))
        except Exception:  # report it to the test; the runner stays up for the next request
            write_message(answers, ("error", traceback.format_exc()))


if __name__ == "__main__":
    main()
