"""What every benchmark script shares around its tables: the ``--write PATH`` option, and the file it
writes, which the documentation's performance page includes as it is (``docs/performance/``).

A script builds its parser with ``benchmark_parser`` (its own options, plus ``--write``) and decorates
its ``main(argv=None)`` with ``writes_tables``. The script prints as before; with ``--write PATH``,
what it prints on stdout is also kept and, once ``main`` returns, written to ``PATH`` under a header
that says what made it::

    # command: python -m benchmarks.bench_cut --write docs/performance/cut.txt
    # machine: <CPU model>, <n> cores (<n> usable), <memory> GiB; Linux <release>; Python 3.11.x, numba 0.68.x, NumPy 2.x
    # commit: <short hash>[+dirty]
    # date: <ISO date and time>
    # load: 1-minute load average <a> at the start, <b> at the end; wall <s> s

    <the tables the script printed>

A run that raises writes nothing (an old file stays as it was). The header is read from the machine
and from git when the run has finished, never typed: a table cannot claim another machine or commit
than the one it ran on.
"""
from __future__ import annotations

import argparse
import datetime
import functools
import io
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["benchmark_parser", "writes_tables", "header", "machine", "commit", "HEADER_FIELDS"]

#: the header's fields, in their order (tests/test_benchmark_files.py checks every committed file has them)
HEADER_FIELDS = ("command", "machine", "commit", "date", "load")
#: where the written tables live: files there do not make the tree "dirty" (they are outputs, not code)
TABLES = "docs/performance"
_REPO = Path(__file__).resolve().parent.parent


class _Run:
    """One call of a decorated ``main``: the script's arguments and, once parsed, the path to write."""

    def __init__(self, script: str, argv: list[str]):
        self.script, self.argv = script, argv
        self.path: str | None = None
        self.kept: io.StringIO | None = None


_RUNS: list[_Run] = []       # a stack: a benchmark's main may call another's (each writes its own file)


class _BenchmarkParser(argparse.ArgumentParser):
    def parse_args(self, args=None, namespace=None):
        parsed = super().parse_args(args, namespace)
        if parsed.write is not None:
            if not _RUNS:
                self.error("--write needs the script's main decorated with benchmarks._report.writes_tables")
            _RUNS[-1].path = parsed.write
        return parsed


def benchmark_parser(doc: str | None, **kwargs) -> argparse.ArgumentParser:
    """The argument parser of a benchmark script: described by the first paragraph of ``doc`` (the
    module's docstring), with ``--write PATH`` added; the script adds its own options."""
    kwargs.setdefault("description", " ".join(doc.strip().split("\n\n")[0].split()) if doc else None)
    parser = _BenchmarkParser(**kwargs)
    parser.add_argument("--write", metavar="PATH",
                        help="also write what is printed to PATH, under a header naming the command, the "
                             "machine, the commit and the date (docs/performance/NAME.txt, which the "
                             "documentation includes)")
    return parser


class _Tee(io.TextIOBase):
    """Writes to the real stdout and keeps a copy."""

    def __init__(self, out, kept: io.StringIO):
        self.out, self.kept = out, kept

    def write(self, text: str) -> int:
        self.kept.write(text)
        return self.out.write(text)

    def flush(self) -> None:
        self.out.flush()

    def fileno(self) -> int:
        return self.out.fileno()

    @property
    def encoding(self):
        return getattr(self.out, "encoding", "utf-8")


def writes_tables(main):
    """Decorator of a benchmark's ``main(argv=None)``: with ``--write PATH`` among its arguments, what
    ``main`` prints on stdout is also written to ``PATH`` under ``header``'s lines once it returns."""

    @functools.wraps(main)
    def wrapper(argv=None):
        argv = list(sys.argv[1:] if argv is None else argv)
        run = _Run(Path(main.__code__.co_filename).stem, argv)
        started, load = time.perf_counter(), _load()
        _RUNS.append(run)
        real = sys.stdout
        run.kept = io.StringIO()
        sys.stdout = _Tee(real, run.kept)      # kept always (the path is known once the parser has run)
        try:
            result = main(argv)
        finally:
            sys.stdout = real
            _RUNS.pop()
        if run.path is not None:
            lines = header(f"python -m benchmarks.{run.script} {shlex.join(argv)}".rstrip(),
                           load, _load(), time.perf_counter() - started)
            text = run.kept.getvalue().strip("\n")
            path = Path(run.path)
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text("\n".join(lines) + "\n\n" + text + "\n", encoding="utf-8")
            print(f"(written to {path})", file=sys.stderr)
        return result

    return wrapper


def header(command: str, load_before: float | None = None, load_after: float | None = None,
           wall: float | None = None) -> list[str]:
    """The header lines of a written table (``# field: value``, in ``HEADER_FIELDS``' order)."""
    def fmt(load):
        return "?" if load is None else f"{load:.2f}"
    seconds = "?" if wall is None else f"{wall:.0f}"
    return [f"# command: {command}",
            f"# machine: {machine()}",
            f"# commit: {commit()}",
            f"# date: {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}",
            f"# load: 1-minute load average {fmt(load_before)} at the start, {fmt(load_after)} at the end; "
            f"wall {seconds} s"]


def machine() -> str:
    """CPU model, cores (and those this process may use), memory, OS release and the versions that
    decide the machine code: Python, numba, NumPy."""
    import numba
    import numpy
    model = _cpuinfo("model name") or platform.processor() or platform.machine()
    cores = os.cpu_count() or 0
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores
    memory = _meminfo_gib()
    return (f"{model}, {cores} cores ({usable} usable), "
            f"{'?' if memory is None else f'{memory:.0f}'} GiB; {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, numba {numba.__version__}, NumPy {numpy.__version__}")


def commit() -> str:
    """The short hash of the checkout's HEAD, with ``+dirty`` when its files (tracked or new, outside
    ``docs/performance``) differ from it; ``unknown`` outside a git checkout."""
    try:
        head = _git("rev-parse", "--short", "HEAD").strip()
        changes = _git("status", "--porcelain", "--", ".", f":(exclude){TABLES}")
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return head + ("+dirty" if changes.strip() else "")


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=_REPO, capture_output=True, text=True, check=True).stdout


def _cpuinfo(field: str) -> str | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            name, _, value = line.partition(":")
            if name.strip() == field:
                return " ".join(value.split())
    except OSError:
        pass
    return None


def _meminfo_gib() -> float | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) / 2**20          # kB -> GiB
    except (OSError, ValueError, IndexError):
        pass
    return None


def _load() -> float | None:
    try:
        return os.getloadavg()[0]
    except OSError:
        return None
