"""The ``cgaskin`` command line."""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path


def _build(args) -> int:
    if args.kernels:
        if args.catalogue or args.out or args.target or args.report:
            print("cgaskin build: error: --kernels builds the shipped kernels alone (no --catalogue, --out, "
                  "--target or --report)", file=sys.stderr)
            return 2
        return _check_kernels() if args.check else _build_kernels(args.jobs)
    if (args.catalogue is None) != (args.out is None):
        print("cgaskin build: error: --catalogue FILE and --out DIR go together", file=sys.stderr)
        return 2
    try:
        from ..codegen import build, catalogue_build
    except ImportError as exc:                        # sympy is a build-time extra
        print(f"cgaskin build needs sympy: pip install 'cgaskin[build]' ({exc})", file=sys.stderr)
        return 2
    from ..codegen.ir import CodegenError
    from ..codegen.targets import parse_targets
    try:
        targets = None if args.target is None else parse_targets(args.target)
        if args.catalogue is None:
            stale = build.build(check=args.check, report=args.report, targets=targets)
        else:
            # (no --target: numba and every target whose stamped files are beside the module already)
            stale = catalogue_build.build_catalogue(args.catalogue, args.out, check=args.check, report=args.report,
                                                    targets=targets)
    except CodegenError as exc:                       # the user's catalogue or arguments: one line, no traceback
        print(f"cgaskin build: error: {exc}", file=sys.stderr)
        return 2
    if args.check and args.catalogue is None:
        return max(1 if stale else 0, _check_kernels())
    return 1 if (args.check and stale) else 0


def _check_kernels() -> int:
    """List the shipped kernels stale against the sources; 1 when there is one."""
    from .ship import check_kernels
    stale, notes = check_kernels()
    for note in notes:
        print(f"cgaskin build: {note}")
    if stale:
        print("stale shipped kernels (rebuild them with `cgaskin build --kernels`):\n  " + "\n  ".join(stale))
        return 1
    return 0


def _build_kernels(jobs) -> int:
    from ..errors import KernelBuildError
    from .ship import build_kernels
    try:
        built = build_kernels(jobs)
    except KernelBuildError as exc:
        print(f"cgaskin build: error: {exc}", file=sys.stderr)
        return 1
    print(f"built {len(built)} shipped kernels" if built else "the shipped kernels are up to date")
    return 0


def _verify(args) -> int:
    try:
        from ..codegen import verify
    except ImportError as exc:                        # sympy and clifford: the test extra
        print(f"cgaskin verify: error: {exc}", file=sys.stderr)
        return 2
    from ..codegen.ir import CodegenError
    try:
        report = verify.verify_catalogue(args.catalogue, args.out, examples=args.examples)
    except verify.VerificationError as exc:
        print(exc.report.table() if exc.report else "")
        print(f"cgaskin verify: FAIL: {exc}", file=sys.stderr)
        return 1
    except CodegenError as exc:                       # the user's catalogue: one line, no traceback
        print(f"cgaskin verify: error: {exc}", file=sys.stderr)
        return 2
    print(report.table())
    return 0


BENCHMARKS = {"skinning": "bench_skinning", "frame": "bench_frame", "animation": "bench_animation",
              "cut": "bench_cut", "tear": "bench_tear", "drill": "bench_drill", "batch": "bench_batch",
              "shipped": "bench_shipped", "cold": "bench_cold_start",
              "fig1": "fig1_compare"}


def benchmarks_root() -> Path | None:
    """The source tree whose ``benchmarks/`` folder ``cgaskin bench`` runs: the one this cgaskin is
    installed from (an editable install: ``cgaskin`` is its ``runtime/``), else the current folder
    when it is such a tree; None when neither is (a wheel ships no benchmarks). The console script
    needs this: unlike ``python -m cgaskin``, it does not have the current folder on ``sys.path``."""
    for root in (Path(__file__).resolve().parents[2], Path.cwd()):
        if (root / "pyproject.toml").is_file() and (root / "benchmarks" / "__init__.py").is_file():
            return root
    return None


def _bench(args) -> int:
    import importlib
    root = benchmarks_root()
    if root is None:
        print("cgaskin bench: error: the benchmarks are not installed with cgaskin (they live in the "
              "benchmarks/ folder of its source tree): clone the repository, `pip install -e '.[bench]'` "
              "in it, then run `cgaskin bench` (or `python -m cgaskin bench` from that folder)", file=sys.stderr)
        return 2
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    try:
        module = importlib.import_module(f"benchmarks.{BENCHMARKS[args.which]}")
    except ImportError as exc:          # a baseline the benchmark compares against (the [bench] extra)
        print(f"cgaskin bench: error: the {args.which} benchmark ({root / 'benchmarks'}) needs "
              f"{exc.name or exc}: pip install 'cgaskin[bench]'", file=sys.stderr)
        return 2
    module.main(args.rest)
    return 0


def _precompile(args) -> int:
    from .precompile import precompile
    if precompile(args.jobs, verbose=True) == 0:
        print("every kernel is compiled and cached already")
    return 0


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings on the command line are messages to the user, not source locations."""
    print(f"cgaskin: warning: {message}", file=sys.stderr if file is None else file)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="cgaskin", description="Deform, cut and tear skinned models with CGA.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("build", help="regenerate the numba kernels in generated/ from codegen/, or build "
                                     "a catalogue of @kernel functions into a module")
    p.add_argument("--check", action="store_true", help="do not write: fail if generated/ (or the catalogue's "
                                                        "module) is stale, naming the stale kernels")
    p.add_argument("--catalogue", metavar="FILE", help="a Python file (or module name) of @kernel functions "
                                                       "(cgaskin.codegen.kernel)")
    p.add_argument("--out", metavar="DIR", help="with --catalogue: the folder to write FILE's module into "
                                                "(DIR/<FILE stem>.py), or the .py file itself")
    p.add_argument("--target", metavar="LIST", help="comma-separated printers: numba (the default), c, glsl, "
                                                    "wgsl, cuda, js; generated/<target>/ for the built-in catalogue "
                                                    "(kept fresh once there), beside the module for --catalogue")
    p.add_argument("--report", action="store_true", help="print each kernel's operation counts after CSE "
                                                         "(mul, add, div, sqrt, other; hoisted parts apart)")
    p.add_argument("--kernels", action="store_true", help="compile the kernels that ship with the package "
                                                          "(cgaskin/_kernels) where their sources changed, for "
                                                          "a portable x86-64 target, on every core; with "
                                                          "--check: only list the stale ones")
    p.add_argument("--jobs", type=int, default=None, help="with --kernels: processes (default: one per core)")
    p.set_defaults(run=_build)

    p = sub.add_parser("verify", help="run every kernel of a catalogue three ways (generated, clifford, the "
                                      "float64 expansion) on drawn inputs; exit 1 on any disagreement")
    p.add_argument("--catalogue", metavar="FILE", required=True, help="a Python file (or module name) of "
                                                                      "@kernel functions")
    p.add_argument("--examples", type=int, default=50, help="inputs per kernel and range (default 50)")
    p.add_argument("--out", metavar="DIR", default=None, help="build the module here (default: a temporary "
                                                              "folder)")
    p.set_defaults(run=_verify)

    p = sub.add_parser("precompile", help="compile the numba kernels now, on every core (a fresh install "
                                          "otherwise compiles them at their first call, one at a time)")
    p.add_argument("--jobs", type=int, default=None, help="processes (default: one per core)")
    p.set_defaults(run=_precompile)

    p = sub.add_parser("bench", help="run a benchmark (prints tables)")
    p.add_argument("which", choices=list(BENCHMARKS), nargs="?", default="skinning")
    p.add_argument("rest", nargs=argparse.REMAINDER, help="options passed to the benchmark")
    p.set_defaults(run=_bench)

    from . import commands                            # the model commands (demo, skin, cut, drill, tear)
    commands.register(sub)

    args = parser.parse_args(argv)
    from ..errors import CgaskinError
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            if getattr(args, "check_options", None):     # incomplete or conflicting options, before any work
                args.check_options(args)
            return args.run(args)
    except (CgaskinError, OSError) as exc:
        # bad input is the user's to fix: say what is wrong, without a traceback
        print(f"cgaskin {args.command}: error: {_message(exc)}", file=sys.stderr)
        return 2


def _message(exc: Exception) -> str:
    """One line: a system error as "<file>: <reason>" (not "[Errno 20] ..."), any other as it says."""
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.filename}: {exc.strerror}" if exc.filename else exc.strerror
    return str(exc)


if __name__ == "__main__":
    sys.exit(main())
