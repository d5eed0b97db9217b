"""cgaskin batch: items per second on a LocalCluster of 1 and of 2 worker processes, same spec, one run.

    python -m benchmarks.bench_batch [--count 5] [--repeat 3]

The spec: Fox.glb, Arm5.glb and 3Cylinder4bones.glb at rest with a random dilation, each with
``--count`` cuts, tears and drills and one posed copy (3 x (3 count + 1) items). Each cluster is
started, then warmed by a batch of the same spec with another seed (the workers load the cache of
compiled kernels and the rigs), then timed over ``--repeat`` batches into fresh folders (median):
what a long batch sees per item, the cluster's start (printed apart) left out. Then a fresh worker's
first item: a new cluster of one worker process whose numba cache is an empty folder (a worker on a
new machine), timed from the batch's start to its end (one item), with what that worker loaded from
the shipped kernels and what it compiled. The scaling goal on
a 2-core machine: 2 workers >= 1.7x the items per second of 1. ``ms/item`` is an item's own time on
its worker: when it grows from 1 to 2 workers the workers did not get a core each (the machine's load
average, printed, says what else ran).
"""
from __future__ import annotations

import logging
import os
import statistics
import tempfile
import time
from pathlib import Path

from ._report import benchmark_parser, writes_tables
from ._timing import print_table
from .bench_tear import models_dir

MODELS = ("Fox.glb", "Arm5.glb", "3Cylinder4bones.glb")


def _spec(folder: Path, count: int, seed: int) -> Path:
    models = "".join(f'[[models]]\npath = "{models_dir() / name}"\n' for name in MODELS)
    operations = "".join(f'[[operations]]\nkind = "{kind}"\ncount = {count}\n' for kind in ("cut", "tear", "drill"))
    path = folder / f"spec{seed}.toml"
    path.write_text(f"seed = {seed}\n{models}[[poses]]\nrest = true\n"
                    f"edits = {{ dilate = {{ joint = 2, range = [0.8, 1.2] }} }}\n{operations}"
                    f'[[operations]]\nkind = "none"\n', encoding="utf-8")
    return path


def measure(workers: int, count: int, repeat: int, folder: Path) -> list:
    """[workers, items, start s, seconds per batch (median), items/s, failed items] on a fresh cluster."""
    from dask.distributed import Client, LocalCluster

    from cgaskin.batch import run
    start = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, silence_logs=logging.ERROR,
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        started = time.perf_counter() - start
        run(_spec(folder, count, seed=1000 + workers), folder / f"warm{workers}", client=client)
        seconds, manifest = [], None
        for k in range(repeat):
            begin = time.perf_counter()
            manifest = run(_spec(folder, count, seed=1), folder / f"w{workers}-{k}", client=client)
            seconds.append(time.perf_counter() - begin)
    median = statistics.median(seconds)
    # an item's own seconds on its worker: when it grows with the workers, they share cores (another load)
    item_ms = 1e3 * statistics.mean(r.seconds for r in manifest.rows)
    return [workers, len(manifest.rows), started, median, item_ms, len(manifest.rows) / median, len(manifest.errors)]


def _kernel_counts() -> tuple:
    """(kernels loaded from the shipped ones, kernels compiled) in this (worker) process."""
    from cgaskin._shared import shipped
    from cgaskin.app.precompile import KERNELS, _dispatcher
    compiled = sum(sum(_dispatcher(i)[0].stats.cache_misses.values()) for i in range(len(KERNELS)))
    return sum(shipped.LOADED.values()), compiled


def fresh_worker(folder: Path, shipped: bool = True) -> list:
    """[seconds of a one-item batch on a new worker with an empty numba cache, kernels it loaded, compiled]
    (``shipped=False``: a worker where the shipped kernels do not serve)."""
    from dask.distributed import Client, LocalCluster

    from cgaskin.batch import run
    spec = folder / "one.toml"
    spec.write_text(f'seed = 7\n[[models]]\npath = "{models_dir() / MODELS[0]}"\n[[poses]]\nrest = true\n'
                    f'[[operations]]\nkind = "tear"\ncount = 1\n', encoding="utf-8")
    cache = folder / "fresh-numba-cache"
    cache.mkdir()
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, silence_logs=logging.ERROR,
                      dashboard_address=":0", env={"NUMBA_CACHE_DIR": str(cache),
                                                   "CGASKIN_SHIPPED_KERNELS": "1" if shipped else "0"}) as cluster, \
            Client(cluster) as client:
        begin = time.perf_counter()
        manifest = run(spec, folder / "fresh", client=client)
        seconds = time.perf_counter() - begin
        (loaded, compiled), = client.run(_kernel_counts).values()
    assert len(manifest.rows) == 1 and not manifest.errors, manifest.errors
    return [seconds, loaded, compiled]


@writes_tables
def main(argv=None):
    parser = benchmark_parser(__doc__)
    parser.add_argument("--count", type=int, default=5, help="instances of each operation per model")
    parser.add_argument("--repeat", type=int, default=3, help="timed batches per cluster (median)")
    args = parser.parse_args(argv)
    from cgaskin.app.precompile import default_jobs, precompile
    precompile()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        rows = [measure(n, args.count, args.repeat, Path(tmp)) for n in (1, 2)]
        fresh = fresh_worker(Path(tmp))
    rows[0].append(1.0)
    rows[1].append(rows[1][5] / rows[0][5])
    print_table(f"cgaskin batch on a LocalCluster (median of the timed batches; start apart; {default_jobs()} cores, "
                f"load average {load:.2f} before, {os.getloadavg()[0]:.2f} after)",
                ["workers", "items", "start s", "batch s", "ms/item", "items/s", "failed", "x 1 worker"], rows)
    print_table("a fresh worker's first item (a new worker process, an empty numba cache; one tear of Fox)",
                ["first item s", "kernels loaded", "kernels compiled"], [fresh])


if __name__ == "__main__":
    main()
