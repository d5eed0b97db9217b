"""The one jit wrapper of the runtime, and the record of what ``cgaskin.precompile`` compiles.

Every compiled function is either a ``kernel`` (called from Python) or a ``helper`` (called only from
other compiled functions; a ``callee`` is a helper that precompile compiles ahead), each with one
fixed set of options:

* shipped and cached: the package ships every recorded signature compiled (``shipped``), and what
  compiles is cached beside the source; both are keyed by every cgaskin module the kernel imports
  (``cache_keys.keyed``), so a changed helper recompiles the kernels that use it;
* ``nogil=True``: callers may run kernels in threads;
* ``error_model="numpy"``: division by zero gives inf/NaN like numpy (the kernels check for it)
  instead of raising from compiled code;
* helpers add ``no_cpython_wrapper=True``: numba builds no Python entry point for them, which
  shortens a cold start by about a tenth.

A kernel lists the argument types the runtime's own calls give it, where it is defined
(``@kernel((F2, I1), cost=0.4)``); generated kernels that the runtime calls are recorded where they
are called (``precompiled(K.some_batch, (F2r, F2), cost=0.3)``). ``SIGNATURES`` collects them as the
modules are imported; ``cgaskin.precompile`` compiles the ones numba's cache lacks, on every core.
``cost`` is the seconds one signature takes to compile cold on a 2-core machine, used only to share
the work out evenly. A *fused* kernel (``@kernel(..., fused=True)``) calls big helpers that are
``callee``s with their signatures: precompile compiles it after everything else, so that those callees
were compiled in parallel first and it only loads them (numba's cache: the same machine code).
"""
from __future__ import annotations

from typing import NamedTuple

from numba import njit, types

from . import shipped
from .cache_keys import is_keyed, keyed

__all__ = ["kernel", "helper", "cache_generated", "GENERIC", "WIDE", "inlined", "callee", "precompiled", "record",
           "SIGNATURES", "Signature"]

_OPTIONS = {"nogil": True, "error_model": "numpy"}       # and cached, by ``keyed`` (not numba's cache=True)

# argument types: C-contiguous arrays by dtype and rank ("r": read-only), and scalars
F1, F2, F3 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, ::1]
F4 = types.float64[:, :, :, ::1]
I1, I2 = types.int64[::1], types.int64[:, ::1]
S1, U2 = types.int8[::1], types.uint64[:, ::1]
B1, B2 = types.boolean[::1], types.boolean[:, ::1]
F1r = types.Array(types.float64, 1, "C", readonly=True)
F2r = types.Array(types.float64, 2, "C", readonly=True)
i8, f8, b1 = types.int64, types.float64, types.boolean


def record(*fields):
    """The numba type of a record (a NamedTuple of arrays with these field types) as kernels take
    it: a plain tuple (``tuple(record)``; the kernel unpacks it in field order). numba types a plain
    tuple of arrays in C at each call and a NamedTuple in Python, about 1 µs more per argument."""
    if len(set(fields)) == 1:
        return types.UniTuple(fields[0], len(fields))
    return types.Tuple(list(fields))


#: the CPUs a kernel ships compiled for (``shipped``): every kernel for LLVM's generic x86-64 (any
#: x86-64 runs it); a kernel whose loop the generic CPU runs markedly slower also for x86-64-v3 (AVX2,
#: FMA: every x86-64 CPU since 2013-2015; skinning's blend loop ran at 0.75x the host's speed generic,
#: at 1.0x so), which loads where the CPU has those features
GENERIC, WIDE = ("generic",), ("generic", "x86-64-v3")


class Signature(NamedTuple):
    """One compiled variant that precompile makes: ``module.name`` for ``argtypes`` (``fused``: after
    every other one), shipped compiled for ``targets``."""

    module: str
    name: str
    argtypes: tuple
    cost: float
    fused: bool = False
    targets: tuple = GENERIC


#: every (kernel, argument types) that the runtime calls from Python, in import order
SIGNATURES: list = []


def precompiled(dispatcher, *signatures: tuple, cost: float = 0.3, fused: bool = False, targets: tuple = GENERIC):
    """Record argument types that the runtime calls ``dispatcher`` (a numba kernel) with; returns it."""
    function = getattr(dispatcher, "py_func", dispatcher)       # (a plain function under NUMBA_DISABLE_JIT=1)
    for argtypes in signatures:
        SIGNATURES.append(Signature(function.__module__, function.__name__, tuple(argtypes),
                                    cost, fused, targets))
    return dispatcher


def cache_generated(*modules) -> None:
    """Give every numba function of these generated modules the cache of a ``kernel``: keyed by what
    it imports, and loading the shipped kernels (``cgaskin build`` prints them without numba's
    ``cache=True``: ``codegen.printer.RUNTIME_DECORATOR``)."""
    from numba.core.dispatcher import Dispatcher
    for module in modules:
        for value in vars(module).values():
            if isinstance(value, Dispatcher) and not is_keyed(value):
                keyed(value, shipped=shipped.FOR_KERNELS)


def kernel(*signatures: tuple, cost: float = 0.3, fused: bool = False, targets: tuple = GENERIC):
    """Compile a function that Python calls; ``signatures`` are the argument types of the runtime's
    own calls (precompiled), ``cost`` the cold compile seconds of each (for a ``fused`` one, its own
    seconds once its callees are compiled), ``targets`` the CPUs it ships compiled for."""
    def wrap(function):
        return precompiled(keyed(njit(**_OPTIONS)(function), shipped=shipped.FOR_KERNELS), *signatures, cost=cost,
                           fused=fused, targets=targets)
    return wrap


def helper(function):
    """Compile a function that only other compiled functions call (no Python entry point)."""
    return keyed(njit(**_OPTIONS, no_cpython_wrapper=True)(function), shipped=shipped.FOR_HELPERS)


def inlined(function):
    """A ``helper`` whose body numba types into each caller instead of calling it: for a short body
    called in a hot loop, where a call's reference counting of its array arguments (atomic operations)
    costs as much as the body. Keep it to helpers with one or two callers (each caller types it again)."""
    return njit(**_OPTIONS, inline="always")(function)


def callee(*signatures: tuple, cost: float):
    """A ``helper`` that a fused kernel calls with these argument types, compiled ahead by precompile
    (in parallel with the other kernels; ``cost`` as for ``kernel``)."""
    def wrap(function):
        return precompiled(helper(function), *signatures, cost=cost)
    return wrap
