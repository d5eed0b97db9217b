"""What a fresh install waits for: the first tear, skin, cut and drill in one process, and ``cgaskin demo``,
each with an empty numba cache: the kernels it loads from those shipped compiled with the package, and
the compile seconds of every function compiled.

    python -m benchmarks.bench_cold_start [first_tear|first_skin|first_cut|first_drill|demo ...] [--top N] [--variants]
                                          [--phases] [--compiled]

Each case runs in a child process whose ``NUMBA_CACHE_DIR`` is a new empty folder (a fresh install:
nothing compiled, nothing cached). ``--compiled`` runs it without the shipped kernels too
(``CGASKIN_SHIPPED_KERNELS=0``: what an install for another numba, NumPy or Python compiles, or one
whose sources were edited). numba's event API (``numba:compile`` events) gives each function's
compile time; a function's *own* seconds leave out the functions compiled while it was (its callees),
so that the own column adds up to the compile total. Goals (issue 23, 2-core machine): first tear
<= 15 s, cold demo <= 20 s.

``--phases`` splits the wall time: LLVM's function passes, its module passes and its machine code
(timed around numba's ``CPUCodeLibrary`` methods: internals, for this measurement only), the rest
being numba's typing and lowering in Python; and the LLVM instructions each library adds itself
against those its module passes see once its callees are linked in (numba links every callee's code
into its caller and optimises and emits it again there). Measured on this 2-core machine (first tear,
capsule_arm, numba 0.68): 68 s = 5.5 s function passes + 16 s module passes + 14 s machine code +
~31 s typing and lowering; 88k own instructions, 339k seen by module passes (3.8x).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

from ._report import benchmark_parser, writes_tables

CASES = {
    "first_skin": "import cgaskin; rig = cgaskin.capsule_arm(); cgaskin.skin(rig, rig.pose('wave', 1.0))",
    "first_cut": "import cgaskin; rig = cgaskin.capsule_arm(); cgaskin.cut(rig, [1, 0, 0], [1.2, 0, 0])",
    "first_tear": ("import cgaskin; rig = cgaskin.capsule_arm(); "
                   "cgaskin.tear(rig, ([0.6, 0.05, 1.0], [0.6, 0.05, 0.0]), ([1.2, 0.05, 1.0], [1.2, 0.05, 0.0]))"),
    "first_drill": "import cgaskin; rig = cgaskin.capsule_arm(); cgaskin.drill(rig, [1.0, 0, -1], [1.0, 0, 1], 0.1)",
    "demo": "from cgaskin.app.cli import main; import sys, tempfile; main(['demo', '--out', tempfile.mkdtemp()])",
}

# run in the child: the case, with numba's compile events recorded (and with --phases, LLVM's share)
_CHILD = """
import json, sys, time
from numba.core import codegen, event
phases = dict.fromkeys(["function passes", "module passes", "machine code"], 0.0)
instructions = {"own": 0, "linked": 0}


def _instructions(module):
    return sum(1 for f in module.functions if not f.is_declaration for b in f.blocks for i in b.instructions)


def _timed(name, key, count=None):
    method = getattr(codegen.CPUCodeLibrary, name)

    def timed(library, *args):
        if count:
            instructions[count] += _instructions(library._final_module)
        started = time.perf_counter()
        try:
            return method(library, *args)
        finally:
            phases[key] += time.perf_counter() - started
    setattr(codegen.CPUCodeLibrary, name, timed)


if sys.argv[2] == "phases":
    _timed("_optimize_functions", "function passes")
    _timed("_optimize_final_module", "module passes", "linked")
    _timed("_finalize_final_module", "machine code")
    finalize = codegen.CPUCodeLibrary.finalize

    def counted(library):
        instructions["own"] += _instructions(library._final_module)
        return finalize(library)
    codegen.CPUCodeLibrary.finalize = counted
start = time.perf_counter()
with event.install_recorder("numba:compile") as recorder:
    exec(sys.argv[1])
wall = time.perf_counter() - start
from cgaskin._shared import shipped
events = [(t, e.is_start, e.data["dispatcher"].py_func.__qualname__ + " " + e.data["dispatcher"].py_func.__module__,
           str(e.data.get("args"))) for t, e in recorder.buffer]
print("@@" + json.dumps({"wall": wall, "events": events, "phases": phases, "instructions": instructions,
                        "loaded": sum(shipped.LOADED.values())}))
"""


def _own_seconds(events: list) -> dict:
    """{(function, args): [own seconds, compiles]} from nested start/end events (one thread)."""
    own, stack = {}, []
    for t, is_start, name, args in events:
        if is_start:
            stack.append([name, args, t, 0.0])
            continue
        name, args, started, children = stack.pop()
        inclusive = t - started
        entry = own.setdefault((name, args), [0.0, 0])
        entry[0] += inclusive - children
        entry[1] += 1
        if stack:
            stack[-1][3] += inclusive
    return own


def run_case(case: str, phases: bool = False, shipped: bool = True) -> tuple[float, dict, dict]:
    """Wall seconds of ``case`` in a fresh process with an empty cache, its compile table, and (with
    ``phases``) LLVM's seconds and instruction counts (else zeros), with the count of kernels loaded
    from the shipped ones (``shipped=False``: none)."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, CGASKIN_SHIPPED_KERNELS="1" if shipped else "0")
        done = subprocess.run([sys.executable, "-c", _CHILD, CASES[case], "phases" if phases else "-"], env=env,
                              capture_output=True, text=True, check=True)
    line = next(line for line in done.stdout.splitlines() if line.startswith("@@"))
    result = json.loads(line[2:])
    return result["wall"], _own_seconds(result["events"]), {**result["phases"], **result["instructions"],
                                                            "loaded": result["loaded"]}


@writes_tables
def main(argv=None) -> None:
    parser = benchmark_parser(__doc__)
    parser.add_argument("cases", nargs="*", metavar="CASE",
                        help=f"cases to run, of {', '.join(CASES)} (default: first_tear demo)")
    parser.add_argument("--top", type=int, default=15, help="functions listed per case, by own compile seconds")
    parser.add_argument("--variants", action="store_true", help="also list every compiled signature")
    parser.add_argument("--phases", action="store_true", help="split the wall time into LLVM's phases")
    parser.add_argument("--compiled", action="store_true", help="also run each case without the shipped kernels")
    args = parser.parse_args(argv)
    for case in args.cases:             # (not argparse's choices: with nargs="*" they reject no case at all)
        if case not in CASES:
            parser.error(f"unknown case {case!r}: choose from {', '.join(CASES)}")
    top, variants, phases, compiled = args.top, args.variants, args.phases, args.compiled
    cases = args.cases or ["first_tear", "demo"]
    for case, shipped in [(case, shipped) for case in cases for shipped in ((True, False) if compiled else (True,))]:
        started = time.perf_counter()
        wall, table, llvm = run_case(case, phases, shipped)
        compile_total = sum(seconds for seconds, _ in table.values())
        print(f"\n{case} ({'shipped kernels' if shipped else 'CGASKIN_SHIPPED_KERNELS=0'}): {wall:.1f} s in the "
              f"process ({time.perf_counter() - started:.1f} s with its start), {llvm['loaded']} kernels loaded, "
              f"{compile_total:.1f} s compiling {len(table)} variants")
        if phases:
            in_llvm = llvm["function passes"] + llvm["module passes"] + llvm["machine code"]
            print(f"  LLVM {in_llvm:.1f} s: function passes {llvm['function passes']:.1f} s, module passes "
                  f"{llvm['module passes']:.1f} s, machine code {llvm['machine code']:.1f} s; the rest (numba's "
                  f"typing and lowering, the case's own work) {wall - in_llvm:.1f} s")
            print(f"  LLVM instructions: {llvm['own']} made by the libraries themselves, {llvm['linked']} seen by "
                  f"the module passes with their callees linked in ({llvm['linked'] / max(llvm['own'], 1):.1f}x)")
        by_function = {}
        for (name, _args), (seconds, count) in table.items():
            entry = by_function.setdefault(name, [0.0, 0])
            entry[0] += seconds
            entry[1] += count
        print(f"  {'own s':>6} {'variants':>8}  function")
        for name, (seconds, count) in sorted(by_function.items(), key=lambda kv: -kv[1][0])[:top]:
            print(f"  {seconds:6.2f} {count:8d}  {name}")
        if variants:        # every compiled signature: what compiles more than once, and with what
            print(f"\n  {'own s':>6}  function and argument types")
            for (name, args), (seconds, _) in sorted(table.items()):
                print(f"  {seconds:6.2f}  {name} {args}")


if __name__ == "__main__":
    main()
