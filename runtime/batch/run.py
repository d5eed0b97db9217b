"""Run a batch on Dask: one task per item that the batch folder does not hold yet.

``run(spec, out)`` expands the spec into items (``items.py``), keeps the items that an earlier run
finished (the manifest's row, every file there with its recorded sha256), and submits the others to a
``dask.distributed`` cluster: a ``LocalCluster`` of worker processes by default, or the scheduler at
``scheduler`` (an address), or the caller's ``client``. A task carries an item (paths, hashes,
parameters: a few hundred bytes) and returns its row; the rig is loaded by the worker, once per
process (``operate.py``), so rigs never cross the network. Workers warm numba's cache
(``cgaskin.precompile``) once, before their first item (``Warmup``). The manifest is rewritten
(atomically) about every ``flush_seconds`` while rows come in, so a run killed half-way leaves the
rows of the items it finished, and the next run makes only the others.
"""
from __future__ import annotations

import asyncio
import hashlib
import logging
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .._shared.atomic import TEMPORARY
from ..errors import InvalidInputError
from .items import expand, require_item_memory
from .lock import folder_lock
from .manifest import MANIFEST, read_manifest, reusable_rows, write_manifest
from .operate import TMP_SUFFIX, Row, item_row
from .spec import Spec, load_spec

__all__ = ["run", "Manifest", "Warmup"]


@dataclass(frozen=True)
class Manifest:
    """What a run left: its rows, as written to the manifest.

    Parameters
    ----------
    path : pathlib.Path
        The manifest file (``out/manifest.parquet``).
    rows : tuple of Row
        One per item, in spec order.
    computed : int
        How many items this run made.
    kept : int
        How many an earlier run had made (their files checked).
    dashboard : str, optional
        The cluster's dashboard address (None when it has none).

    Examples
    --------
    >>> manifest = cgaskin.batch.run("spec.toml", "out", workers=2)       # doctest: +SKIP
    >>> manifest.computed, manifest.kept, manifest.errors                  # doctest: +SKIP
    (4, 0, [])
    """

    path: Path
    rows: tuple
    computed: int
    kept: int
    dashboard: str | None = None

    @property
    def errors(self) -> list:
        """The rows whose item failed."""
        return [r for r in self.rows if r.error is not None]

    def table(self):
        """The manifest as a table, read from ``path``.

        Returns
        -------
        pyarrow.Table
        """
        import pyarrow.parquet as pq
        return pq.read_table(self.path)


class Warmup:
    """A Dask worker plugin: ``cgaskin.precompile(jobs=1)`` once per worker, before its first task
    (in a thread, so that a cold cache's minute of compiling does not stall the worker's heartbeats).
    Made a ``WorkerPlugin`` subclass at first use (``_warmup_plugin``), so importing this module
    does not import dask."""

    name = "cgaskin-precompile"

    async def setup(self, worker):
        await asyncio.get_running_loop().run_in_executor(None, _precompile_one_process)


#: whether this (worker) process has run precompile: a client registering the plugin again (each
#: ``run`` on a long-lived cluster does) then costs nothing
_WARM = []


def _precompile_one_process() -> None:
    if not _WARM:
        from ..app.precompile import precompile
        precompile(jobs=1)
        _WARM.append(True)


def _warmup_plugin():
    from distributed.diagnostics.plugin import WorkerPlugin
    return type("CgaskinWarmup", (Warmup, WorkerPlugin), {"__module__": __name__})()


#: the memory a run holds per item in this process: the item, its row, the manifest's columns and the
#: Dask future and scheduler task that make it (a few kB each), with room
RUN_ITEM_BYTES = 16 << 10


def run(spec, out, client=None, workers: int | None = None, scheduler: str | None = None,
        progress: bool = False, flush_seconds: float = 1.0, max_memory: int | None = None) -> Manifest:
    """Make every item of a spec under a batch folder (``out/items/``, ``out/manifest.parquet``).

    Parameters
    ----------
    spec : str or os.PathLike or Spec
        The TOML spec's path, or a ``Spec`` (``load_spec``).
    out : str or os.PathLike
        The batch folder (made if absent); items already there (manifest row + files with their
        sha256) are kept, the others made.
    client : dask.distributed.Client, optional
        A client to run on (left open); else a cluster is made and closed.
    workers : int, optional
        Worker processes of the default ``LocalCluster`` (default: one per core).
    scheduler : str, optional
        The address of a running Dask scheduler (``tcp://host:8786``) instead of a local cluster;
        its workers need cgaskin installed and the model files and ``out`` at the same paths.
    progress : bool, optional
        Draw a progress bar (and print the dashboard address) on stderr.
    flush_seconds : float, optional
        How often the manifest is rewritten while items finish.
    max_memory : int, optional
        Bytes; more items than this run can hold in it (about ``RUN_ITEM_BYTES`` each) are refused
        (the memory available is a limit in any case).

    Returns
    -------
    Manifest
        Items that fail are rows with an ``error``; nothing raises for them.

    Raises
    ------
    InvalidInputError
        A bad spec or conflicting arguments (``MemoryLimitError``: more items than the memory
        holds), before any cluster starts.
    FolderInUseError
        Another run holds ``out`` (one run per folder: ``lock.py``).

    Examples
    --------
    >>> manifest = cgaskin.batch.run("spec.toml", "out", workers=2)       # doctest: +SKIP
    >>> [row.files for row in manifest.rows][:1]                            # doctest: +SKIP
    [('items/3a7b4b3a153b4529.a.glb', 'items/3a7b4b3a153b4529.b.glb')]
    """
    if sum(x is not None for x in (client, scheduler)) > 1:
        raise InvalidInputError("give a client or a scheduler address, not both")
    if workers is not None and (client is not None or scheduler is not None):
        raise InvalidInputError("workers is the size of the local cluster: with a client or a scheduler, "
                                "the cluster has its own workers")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InvalidInputError(f"workers must be a whole number >= 1, got {workers!r}")
    spec = spec if isinstance(spec, Spec) else load_spec(spec)
    require_item_memory(spec, RUN_ITEM_BYTES, max_memory)
    out = Path(out).resolve()
    (out / "items").mkdir(parents=True, exist_ok=True)
    with folder_lock(out):                     # (FolderInUseError while another run holds the folder)
        # what a killed run was writing: no other run writes here while the lock is held
        manifest_temporary = f"{Path(MANIFEST).stem}.*{TEMPORARY}{Path(MANIFEST).suffix}"
        for stale in [*(out / "items").glob("*" + TMP_SUFFIX), *out.glob(manifest_temporary)]:
            stale.unlink(missing_ok=True)
        return _run_locked(spec, out, client, workers, scheduler, progress, flush_seconds)


def _run_locked(spec: Spec, out: Path, client, workers, scheduler, progress: bool, flush_seconds: float) -> Manifest:
    """``run`` in the folder ``out``, which it holds."""
    items = expand(spec)
    manifest_path = out / MANIFEST
    done = reusable_rows(read_manifest(manifest_path), items, out)
    todo = [item for item in items if item.id not in done]
    computed: dict = {}

    def flush():
        write_manifest([done.get(i.id) or computed[i.id] for i in items if i.id in done or i.id in computed],
                       manifest_path)

    dashboard = None
    if todo:
        from dask.distributed import Client, LocalCluster
        owned = []
        try:
            if client is None:
                if scheduler is None:
                    # compile here, on every core, before the workers start: they then only load the cache
                    from ..app.precompile import default_jobs, precompile
                    precompile(verbose=progress)
                    cluster = LocalCluster(n_workers=workers or default_jobs(), threads_per_worker=1, processes=True,
                                           silence_logs=logging.ERROR)
                    owned.append(cluster)
                    client = Client(cluster)
                else:
                    client = Client(scheduler)
                owned.append(client)
            if "dashboard" in client.scheduler_info().get("services", {}):
                dashboard = client.dashboard_link
            if progress:
                print(f"batch: {len(todo)} of {len(items)} items to make on {len(client.scheduler_info()['workers'])} "
                      f"worker(s)" + (f"; dashboard: {dashboard}" if dashboard else ""), file=sys.stderr, flush=True)
            client.register_plugin(_warmup_plugin())
            _compute(client, todo, out, computed, flush, flush_seconds, progress)
        finally:
            flush()                    # (interrupted too: the rows that came in are kept)
            for thing in reversed(owned):
                thing.close()
    else:
        flush()
    rows = tuple(done.get(i.id) or computed[i.id] for i in items)
    return Manifest(manifest_path, rows, len(computed), len(done), dashboard)


def _compute(client, todo, out: Path, computed: dict, flush, flush_seconds: float, progress: bool) -> None:
    """Submit one task per item, collect the rows as they come, flushing the manifest now and then."""
    from dask.distributed import as_completed
    # keys name the item and the folder: two batches on one scheduler never share a task
    folder = hashlib.sha256(str(out).encode()).hexdigest()[:8]
    futures = {client.submit(item_row, item, str(out), key=f"cgaskin-item-{item.id}-{folder}", pure=False): item
               for item in todo}
    start = last = time.monotonic()
    try:
        # (results come with the completions, in batches: no round trip to the scheduler per item)
        for future, result in as_completed(futures, with_results=True, raise_errors=False):
            item = futures[future]
            if future.status == "error":          # the task itself failed (a worker died under it)
                exc = result[1] if isinstance(result, tuple) else result
                computed[item.id] = Row(item.id, item.model, item.pose_label, item.operation, "{}", (), (), (),
                                        0.0, (), f"{type(exc).__name__}: {exc}".splitlines()[0])
            else:
                computed[item.id] = result
            future.release()
            if time.monotonic() - last >= flush_seconds or len(computed) == 1:
                flush()
                last = time.monotonic()
            if progress:
                _bar(len(computed), len(todo), time.monotonic() - start)
    finally:
        if progress and computed:          # (interrupted too: a message then starts on a line of its own)
            print(file=sys.stderr)


def _bar(done: int, total: int, seconds: float) -> None:
    """A one-line progress bar on stderr (redrawn in place)."""
    filled = 30 * done // total
    print(f"\ritems [{'#' * filled}{'.' * (30 - filled)}] {done}/{total} ({done / max(seconds, 1e-9):.1f}/s)",
          end="", file=sys.stderr, flush=True)
