"""``cgaskin batch SPEC.toml --out DIR [--workers N] [--scheduler ADDRESS]``: a dataset on Dask
(``cgaskin.batch``); dask and pyarrow are imported only when the command runs."""
from __future__ import annotations

import sys

from ..errors import InvalidInputError
from .options import add_memory_option, max_memory

#: failed items listed on the console (the manifest's error column has them all)
_LISTED_ERRORS = 5


def _check_batch(args) -> None:
    if args.workers is not None and args.workers < 1:
        raise InvalidInputError(f"--workers {args.workers}: give a number of worker processes >= 1")
    if args.workers is not None and args.scheduler is not None:
        raise InvalidInputError("--workers sizes the local cluster; with --scheduler the cluster has its own "
                                "workers: give one of them")
    max_memory(args)


def _batch(args) -> int:
    from ..batch import load_spec
    spec = load_spec(args.spec)                  # (a bad spec fails here, before dask is imported)
    try:
        from ..batch import run
        import dask.distributed  # noqa: F401  (the [batch] extra: say so rather than fail in the middle)
        import pyarrow  # noqa: F401
    except ImportError as exc:
        raise InvalidInputError(f"cgaskin batch needs {exc.name or exc}: pip install 'cgaskin[batch]'") from None
    manifest = run(spec, args.out, workers=args.workers, scheduler=args.scheduler, progress=True,
                   max_memory=max_memory(args))
    errors = manifest.errors
    print(f"{len(manifest.rows)} items: {manifest.computed} made, {manifest.kept} kept from an earlier run, "
          f"{len(errors)} failed; manifest: {manifest.path}")
    for row in errors[:_LISTED_ERRORS]:
        print(f"cgaskin batch: item {row.id} ({row.model}, {row.pose}, {row.operation}) failed: {row.error}",
              file=sys.stderr)
    if len(errors) > _LISTED_ERRORS:
        print(f"cgaskin batch: ... and {len(errors) - _LISTED_ERRORS} more (the manifest's error column)",
              file=sys.stderr)
    return 0


def register(sub) -> None:
    """Add ``batch`` to the argparse subparsers ``sub``."""
    p = sub.add_parser("batch", help="make a dataset on Dask: every model x pose x operation of a TOML spec, "
                                     "one .glb per item and DIR/manifest.parquet; resumes where it stopped")
    p.add_argument("spec", metavar="SPEC.toml")
    p.add_argument("--out", metavar="DIR", required=True, help="the batch folder (items/, manifest.parquet)")
    p.add_argument("--workers", type=int, default=None, help="worker processes of the local cluster "
                                                             "(default: one per core)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on this Dask scheduler (tcp://host:8786) instead of a local cluster")
    add_memory_option(p)
    p.set_defaults(run=_batch, check_options=_check_batch)
