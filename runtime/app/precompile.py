"""Compile the runtime's numba kernels before their first call, on every core.

numba compiles a kernel at its first call and caches the machine code beside the source (or under
``NUMBA_CACHE_DIR``). On a fresh install skinning, cutting and tearing once would compile minutes of
kernels, one at a time, on one core. ``precompile()`` finds the kernels of
``KERNELS`` that the cache does not hold yet and compiles them in parallel: this process takes one
share and worker processes the others (one process per core), each writing to the same cache.
Afterwards every first call only loads from the cache.

``KERNELS`` lists each kernel that the Python side calls, with the argument types that the
runtime's own calls give it (arrays it made or converted itself; a kernel called with other types,
say read-only arrays of a caller, is compiled at that call as before), recorded where each kernel
is defined (``cgaskin._shared.jit``). Kernels called only from
other kernels are compiled with them (and without a Python wrapper: ``no_cpython_wrapper``), except the
big callees of a fused kernel (``jit.callee``): those are compiled in parallel first, and the fused
kernels after them, loading them from the cache (one process compiling a fused kernel and all it
calls would take longer than every other kernel together). A test
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

from .._shared.jit import SIGNATURES, Signature
from ..errors import InvalidInputError

__all__ = ["precompile", "missing_kernels", "KERNELS", "Signature"]

#: every kernel the Python side calls, with the argument types of the runtime's own calls: the
#: ``Signature`` records that ``cgaskin._shared.jit`` collects where each kernel is defined (importing
#: ``cgaskin`` imports every module that defines one)
KERNELS = SIGNATURES


def _dispatcher(index: int):
    module, name, argtypes = KERNELS[index][:3]
    return importlib.import_module(module).__dict__[name], argtypes


def _is_cached(dispatcher, argtypes) -> bool:
    """Whether the kernel for these argument types loads without compiling (from the shipped kernels or
    numba's cache). What loads is kept by the dispatcher, as numba's own cache hit does, so that its
    first call does not load it again."""
    from numba.core.compiler_lock import global_compiler_lock
    if tuple(argtypes) in dispatcher.overloads:
        return True
    try:
        with global_compiler_lock:
            cres = dispatcher._cache.load_overload(argtypes, dispatcher.targetctx)
            if cres is not None:
                dispatcher.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
                dispatcher.add_overload(cres)
    except Exception:           # numba's internals moved: count it as missing (costs time, not results)
        return False
    return cres is not None


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


def _in_parallel(shares: list) -> list:
    """Compile the first share here and each other one in a worker process; returns what failed."""
    own, *others = shares
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
    return failed


def default_jobs() -> int:
    """The cores this process may run on (``os.cpu_count()`` counts the machine's)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def missing_kernels() -> list:
    """The kernels that would compile at their first call: neither shipped compiled for this setup nor
    in numba's cache. Those it finds are loaded, so that their first call does not look again.

    Returns
    -------
    list of str
        "module.function" of each missing kernel (empty where every kernel loads).

    Examples
    --------
    >>> from cgaskin.app.precompile import missing_kernels
    >>> missing_kernels()                     # doctest: +SKIP
    []
    """
    return [f"{KERNELS[i].module}.{KERNELS[i].name}" for i in range(len(KERNELS)) if not _is_cached(*_dispatcher(i))]


def precompile(jobs: int | None = None, verbose: bool = False) -> int:
    """Compile ahead, on every core, each kernel that neither the shipped kernels nor numba's cache hold.

    What ``cgaskin precompile`` runs: later processes then load every kernel instead of compiling it
    at its first call. Kernels the cache holds cost a load each; with ``NUMBA_DISABLE_JIT=1`` there
    is nothing to compile.

    Parameters
    ----------
    jobs : int, optional
        Processes to compile in (default: one per core).
    verbose : bool, optional
        Print what it does (on stdout) when there is something to compile.

    Returns
    -------
    int
        How many kernels were missing from the cache.

    Examples
    --------
    >>> cgaskin.precompile(verbose=True)          # doctest: +SKIP
    compiling 12 numba kernels in 2 processes (once: they are cached for later runs)
    compiled in 41.3 s
    12
    """
    from numba.core import config
    if config.DISABLE_JIT:
        return 0
    if jobs is None:
        jobs = default_jobs()
    if isinstance(jobs, bool) or not isinstance(jobs, numbers.Integral) or jobs < 1:
        raise InvalidInputError(f"jobs must be a whole number of processes >= 1, got {jobs!r}")
    jobs = int(jobs)
    start = time.perf_counter()
    missing = [i for i in range(len(KERNELS)) if not _is_cached(*_dispatcher(i))]
    if not missing:
        return 0
    if verbose:
        print(f"compiling {len(missing)} numba kernels in {min(jobs, len(missing))} processes (once: they are "
              f"cached for later runs)", flush=True)
    # fused kernels last: the callees they inline are then in the cache, compiled in parallel
    failed = []
    for stage in ([i for i in missing if not KERNELS[i].fused], [i for i in missing if KERNELS[i].fused]):
        if stage:
            failed += _in_parallel(_shares(stage, jobs))
    if verbose:
        print(f"compiled in {time.perf_counter() - start:.1f} s", flush=True)
        for line in failed:
            print(f"not precompiled ({line}); compiled at its first call instead", flush=True)
    return len(missing)
