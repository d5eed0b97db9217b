"""Timing helpers shared by the benchmark scripts: medians of repeated runs, and table printing."""
from __future__ import annotations

import statistics
import time


def median_seconds(fn, repeat: int = 7, warmup: int = 1, min_time: float = 0.0) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs (after ``warmup`` calls). When one call is
    shorter than ``min_time``, each sample times a loop of calls and divides."""
    for _ in range(warmup):
        fn()
    loops = 1
    if min_time:
        start = time.perf_counter()
        fn()
        once = time.perf_counter() - start
        loops = max(1, int(min_time / max(once, 1e-9)))
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(loops):
            fn()
        samples.append((time.perf_counter() - start) / loops)
    return statistics.median(samples)


def print_table(title: str, header: list[str], rows: list[list]) -> None:
    cells = [header] + [[f"{c:.4g}" if isinstance(c, float) else str(c) for c in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    print(f"\n{title}")
    for n, row in enumerate(cells):
        print("  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(row, widths))))
        if n == 0:
            print("  ".join("-" * w for w in widths))
