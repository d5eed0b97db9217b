"""Timing helpers shared by the benchmark scripts: medians of repeated runs, page faults, and table printing."""
from __future__ import annotations

import resource
import statistics
import time


def minor_faults() -> int:
    """Minor page faults of this process so far: each is a fresh page (4 kB, or 2 MB where the kernel
    maps huge pages) that the operating system mapped and zeroed, time that goes to memory, not work.
    (``cgaskin._shared.memory.minor_page_faults`` is the runtime's, which this module does not import.)"""
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt


def timed(fn, repeat: int = 7, warmup: int = 1, min_time: float = 0.0, before=None) -> tuple[float, float]:
    """Median wall time of ``fn()`` over ``repeat`` runs (after ``warmup`` calls), and the median minor
    page faults per call. When one call is shorter than ``min_time``, each sample times a loop of calls
    and divides. ``before``: called (untimed) ahead of every call, e.g. to time ``fn`` after another
    operation."""
    for _ in range(warmup):
        if before:
            before()
        fn()
    loops = 1
    if min_time:
        start = time.perf_counter()
        fn()
        once = time.perf_counter() - start
        loops = max(1, int(min_time / max(once, 1e-9)))
    samples, faults = [], []
    for _ in range(repeat):
        seconds, flt = 0.0, 0
        if before is None:          # one clock and fault reading around the loop (calls of a few µs)
            flt -= minor_faults()
            start = time.perf_counter()
            for _ in range(loops):
                fn()
            seconds = time.perf_counter() - start
            flt += minor_faults()
        else:
            for _ in range(loops):
                before()
                flt -= minor_faults()
                start = time.perf_counter()
                fn()
                seconds += time.perf_counter() - start
                flt += minor_faults()
        samples.append(seconds / loops)
        faults.append(flt / loops)
    return statistics.median(samples), statistics.median(faults)


def median_seconds(fn, repeat: int = 7, warmup: int = 1, min_time: float = 0.0) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs (after ``warmup`` calls). When one call is
    shorter than ``min_time``, each sample times a loop of calls and divides."""
    return timed(fn, repeat, warmup, min_time)[0]


def print_table(title: str, header: list[str], rows: list[list]) -> None:
    cells = [header] + [[f"{c:.4g}" if isinstance(c, float) else str(c) for c in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    print(f"\n{title}")
    for n, row in enumerate(cells):
        print("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(row, widths))))
        if n == 0:
            print("  ".join("-" * w for w in widths))
