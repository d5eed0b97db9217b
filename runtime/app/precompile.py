"""Compile the runtime's numba kernels before their first call, on every core.

numba compiles a kernel at its first call and caches the machine code beside the source (or under
``NUMBA_CACHE_DIR``). On a fresh install skinning, cutting and tearing once would compile about
35 s of kernels (2-core machine), one at a time, on one core. ``precompile()`` finds the kernels of
``KERNELS`` that the cache does not hold yet and compiles them in parallel: this process takes one
share and worker processes the others (one process per core), each writing to the same cache.
Afterwards every first call only loads from the cache.

``KERNELS`` lists each kernel that the Python side calls, with the argument types that the
runtime's own calls give it (arrays it made or converted itself; a kernel called with other types,
say read-only arrays of a caller, is compiled at that call as before). Kernels called only from
other kernels are compiled with them (and without a Python wrapper: ``no_cpython_wrapper``). A test
runs skinning, cuts and tears after ``precompile()`` and fails if any of them still compiles a
kernel, so the list cannot fall behind the code.
"""
from __future__ import annotations

import importlib
import numbers
import os
import subprocess
import sys
import time

from numba import types

from ..errors import InvalidInputError

__all__ = ["precompile", "KERNELS"]

# argument types: C-contiguous arrays by dtype and rank ("r": read-only), and scalars
F1, F2, F3 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, ::1]
I1, I2 = types.int64[::1], types.int64[:, ::1]
S1, U2 = types.int8[::1], types.uint64[:, ::1]
B1 = types.boolean[::1]
F1r = types.Array(types.float64, 1, "C", readonly=True)
F2r = types.Array(types.float64, 2, "C", readonly=True)
F2ar = types.Array(types.float64, 2, "A", readonly=True)       # np.broadcast_to of one row
i8, f8, b1 = types.int64, types.float64, types.boolean

#: (module, kernel, argument types, relative compile cost: seconds, cold, on a 2-core reference
#: machine; used only to share the work out evenly)
KERNELS = [
    # skinning and poses
    ("cgaskin.generated.skinning", "skin_blend", (F2, I2, F2, F2, F2), 0.4),
    ("cgaskin.animation.pose", "_bone_affines", (I1, F2, F3, B1, I1, F2, F2), 1.8),
    ("cgaskin.generated.kernels", "versor_translator_batch", (F2r, F2), 0.3),
    ("cgaskin.generated.kernels", "versor_rotor_batch", (F2r, F1r, F2), 0.2),
    ("cgaskin.generated.kernels", "versor_rotor_quaternion_batch", (F2r, F2), 0.1),
    ("cgaskin.generated.kernels", "versor_dilator_batch", (F1r, F2), 0.3),
    ("cgaskin.generated.kernels", "gp_versor_versor_batch", (F2r, F2r, F2), 0.7),
    ("cgaskin.generated.kernels", "versor_to_affine_batch", (F2r, F2), 0.4),
    ("cgaskin.generated.kernels", "versor_residual_batch", (F2r, F2), 0.2),
    ("cgaskin.generated.kernels", "reverse_versor_batch", (F2r, F2), 0.2),
    ("cgaskin.generated.kernels", "reverse_versor", (F1r,), 0.2),
    ("cgaskin.generated.kernels", "versor_log_batch", (F2r, F2), 0.5),
    ("cgaskin.generated.kernels", "versor_log", (F1r,), 0.4),
    ("cgaskin.generated.kernels", "versor_exp_batch", (F2r, F2), 0.4),
    ("cgaskin.generated.kernels", "versor_exp", (F1r,), 0.2),
    # welded topology, BVH, weights
    ("cgaskin.surgery.topology", "_weld_positions", (U2,), 0.4),
    ("cgaskin.surgery.topology", "_unique_pairs", (I1, I1), 0.7),
    ("cgaskin.surgery.topology", "_corner_pairs", (I2, I1), 0.2),
    ("cgaskin.surgery.topology", "incidence", (I2, i8), 0.3),
    ("cgaskin.surgery.bvh", "_build", (F2, I2, i8, f8), 1.5),
    ("cgaskin.surgery.new_vertices", "blend_weight_rows", (I2, F2, I2, F2), 0.6),
    # cut
    ("cgaskin.generated.kernels", "plane_from_normal_distance", (F1, f8), 0.1),
    ("cgaskin.generated.kernels", "point_plane_distance_batch", (F2ar, F2, F2), 0.3),
    ("cgaskin.surgery.cut.split", "_classify", (F1, F2, I1, f8), 0.4),
    ("cgaskin.surgery.cut.split", "_split", (F1, F2, I2, I2, I1, I1, S1, I2, I2), 2.1),
    ("cgaskin.surgery.new_vertices", "_place_in_rest", (F2, F2, I2, F2, F2), 1.2),
    ("cgaskin.surgery.cut.assemble", "_lerp_rows", (F2, I1, I1, F1, b1), 0.3),
    ("cgaskin.surgery.cut.assemble", "_assemble", (F2, I1, I1, F2), 0.3),
    ("cgaskin.surgery.cut.assemble", "_assemble", (I2, I1, I1, I2), 0.2),
    ("cgaskin.surgery.cut.cap", "_ear_clip", (F2, I1), 0.5),
    # tear
    ("cgaskin.surgery.tear.locate", "_ends", (F2, F2, I1, I1, I1, I1, I1, F2, F1, F1, F1, F1, F2, I2, F2, I2, I2, I2, I1,
                               I1, I1, f8), 6.0),
    ("cgaskin.surgery.tear.walk", "_walk", (F2, I2, I2, I2, I1, I1, I1, I1, S1, F1, i8, i8, F1, i8, i8, F1), 2.1),
    ("cgaskin.surgery.tear.retriangulate", "_retriangulate", (I2, F2, I2, I2, I2, I2, I1, I1, F2, i8), 4.4),
    ("cgaskin.surgery.tear.slit", "_torn_faces", (I2, F2, I2, I1, I2, I1, I2, I1, I1, I1, i8), 1.0),
    ("cgaskin.surgery.tear.slit", "_open_slit", (I2, I2, I1, F2, F2, F1, I1), 2.9),
    ("cgaskin.surgery.tear.vertex_data", "_vertex_data", (F2, I2, F2, I1, i8, F2, I1, I2, F2, I2, I2, f8, F1, F2, b1), 3.4),
    ("cgaskin.surgery.new_vertices", "_rows", (F2, i8, I2, F2, I1, b1), 0.3),
]


def _dispatcher(index: int):
    module, name, argtypes, _ = KERNELS[index]
    return importlib.import_module(module).__dict__[name], argtypes


def _is_cached(dispatcher, argtypes) -> bool:
    """Whether numba's cache holds the kernel for these argument types (loads it, compiles nothing)."""
    try:
        return dispatcher._cache.load_overload(argtypes, dispatcher.targetctx) is not None
    except Exception:           # numba's internals moved: count it as missing (costs time, not results)
        return False


def _shares(indices: list, jobs: int) -> list:
    """Split ``indices`` into at most ``jobs`` lists of about equal total cost (largest first, each to
    the least loaded list). The signatures of one kernel stay in one list: numba keeps one cache index
    per kernel, and two processes writing it at once would each drop the other's entry."""
    groups = {}
    for i in indices:
        groups.setdefault(KERNELS[i][:2], []).append(i)
    shares = [[] for _ in range(jobs)]
    load = [0.0] * jobs
    for group in sorted(groups.values(), key=lambda g: -sum(KERNELS[i][3] for i in g)):
        j = load.index(min(load))
        shares[j] += group
        load[j] += sum(KERNELS[i][3] for i in group)
    return [share for share in shares if share]


def _compile(indices) -> list:
    """Compile these entries of ``KERNELS``; returns a line for each that failed (it is then compiled
    at its first call, with the types of that call, as without precompile: slower, never wrong)."""
    failed = []
    for i in indices:
        dispatcher, argtypes = _dispatcher(i)
        try:
            dispatcher.compile(argtypes)
        except Exception as exc:
            first_line = (str(exc).splitlines() or [""])[0]
            failed.append(f"{KERNELS[i][0]}.{KERNELS[i][1]}: {type(exc).__name__}: {first_line}")
    return failed


#: a worker process: compiles the entries of ``KERNELS`` given as arguments, reports failures on stderr
_WORKER = ("import sys; from cgaskin.app.precompile import _compile\n"
           "for line in _compile(int(a) for a in sys.argv[1:]): print('FAILED', line, file=sys.stderr)")


def precompile(jobs: int | None = None, verbose: bool = False) -> int:
    """Compile every kernel of ``KERNELS`` that numba's cache does not hold yet, in ``jobs``
    processes (default: one per core); returns how many were missing. Kernels the cache holds cost
    a load each. ``verbose`` prints what it does (on stdout) when there is something to compile.
    With ``NUMBA_DISABLE_JIT=1`` there is nothing to compile."""
    from numba.core import config
    if config.DISABLE_JIT:
        return 0
    if jobs is None:        # the cores this process may run on (os.cpu_count() counts the machine's)
        jobs = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if isinstance(jobs, bool) or not isinstance(jobs, numbers.Integral) or jobs < 1:
        raise InvalidInputError(f"jobs must be a whole number of processes >= 1, got {jobs!r}")
    jobs = int(jobs)
    start = time.perf_counter()
    missing = [i for i in range(len(KERNELS)) if not _is_cached(*_dispatcher(i))]
    if not missing:
        return 0
    own, *others = _shares(missing, jobs)
    if verbose:
        print(f"compiling {len(missing)} numba kernels in {1 + len(others)} processes (once: they are "
              f"cached for later runs)", flush=True)
    workers = [subprocess.Popen([sys.executable, "-c", _WORKER, *map(str, share)], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
               for share in others]
    try:
        failed = _compile(own)
    except BaseException:                  # interrupted: stop the workers too
        for worker in workers:
            worker.kill()
        raise
    finally:
        reports = [worker.communicate()[1] for worker in workers]
    for worker, report in zip(workers, reports):
        lines = report.strip().splitlines()
        failed += [line[len("FAILED "):] for line in lines if line.startswith("FAILED ")]
        if worker.returncode:               # the worker itself failed: the rest of its share is left
            failed.append(f"a compile worker: {lines[-1] if lines else 'no message'}")
    if verbose:
        print(f"compiled in {time.perf_counter() - start:.1f} s", flush=True)
        for line in failed:
            print(f"not precompiled ({line}); compiled at its first call instead", flush=True)
    return len(missing)
