"""The batch folder's manifest (``DIR/manifest.parquet``): one row per item, written atomically with
pyarrow, read back on resume to keep what is done.

Columns: id, model, pose, operation (strings), params (JSON text), files, vertices, faces, sha256
(lists, one entry per output file: a cut has two), seconds (float64), error (string, null when the
item succeeded). ``pyarrow.parquet.read_table(path).to_pandas().explode(["files", "vertices",
"faces", "sha256"])`` gives one row per file.
"""
from __future__ import annotations

from pathlib import Path

from .._shared.atomic import replaced
from .._shared.warn import warn
from ..errors import ManifestWarning
from .items import file_sha256
from .operate import Row, output_names

__all__ = ["MANIFEST", "SCHEMA_COLUMNS", "write_manifest", "read_manifest", "reusable_rows"]

#: the manifest's file name in the batch folder
MANIFEST = "manifest.parquet"
#: the columns in order (Row's fields but ``computed``, which says what this run did)
SCHEMA_COLUMNS = ("id", "model", "pose", "operation", "params", "files", "vertices", "faces", "seconds",
                  "sha256", "error")


def _schema():
    import pyarrow as pa
    text, texts, counts = pa.string(), pa.list_(pa.string()), pa.list_(pa.int64())
    types = {"id": text, "model": text, "pose": text, "operation": text, "params": text, "files": texts,
             "vertices": counts, "faces": counts, "seconds": pa.float64(), "sha256": texts, "error": text}
    return pa.schema([(name, types[name]) for name in SCHEMA_COLUMNS])


def write_manifest(rows, path) -> None:
    """Write ``rows`` (Row records) to ``path`` whole (``atomic.replaced``), so a reader (or a run
    killed while writing) sees the old manifest or the new one, never a part."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    path = Path(path)
    columns = {name: [list(getattr(r, name)) if isinstance(getattr(r, name), tuple) else getattr(r, name)
                      for r in rows] for name in SCHEMA_COLUMNS}
    table = pa.table(columns, schema=_schema())
    with replaced(path) as temporary:
        pq.write_table(table, temporary)


def read_manifest(path) -> list:
    """The rows of a batch folder's manifest.

    Parameters
    ----------
    path : str or os.PathLike
        The manifest (``DIR/manifest.parquet``).

    Returns
    -------
    list of Row
        Its rows (``computed`` False); [] when there is none. A manifest that cannot be read is
        reported with a ``ManifestWarning`` and counts as none (everything is made again).

    Examples
    --------
    >>> cgaskin.batch.read_manifest("no-batch-here/manifest.parquet")
    []
    """
    import pyarrow.parquet as pq
    path = Path(path)
    if not path.exists():
        return []
    try:
        table = pq.read_table(path)
        data = {name: table.column(name).to_pylist() for name in SCHEMA_COLUMNS}
    except Exception as exc:                  # (pyarrow's errors have no common base but Exception)
        warn(f"{path}: cannot read the manifest ({exc}); every item is made again", ManifestWarning)
        return []
    rows = []
    for i in range(table.num_rows):
        values = {name: data[name][i] for name in SCHEMA_COLUMNS}
        for name in ("files", "vertices", "faces", "sha256"):
            values[name] = tuple(values[name] or ())
        rows.append(Row(**values, computed=False))
    return rows


def reusable_rows(rows, items, out) -> dict:
    """id -> row of the earlier ``rows`` that need no work: the item is still in the spec, it
    succeeded, and each of its files is there with the sha256 the row records (read again: a file
    changed or truncated since is made again). Rows with an error are tried again."""
    out = Path(out)
    wanted = {item.id: item for item in items}
    keep = {}
    for row in rows:
        item = wanted.get(row.id)
        if item is None or row.error is not None or list(row.files) != output_names(item):
            continue
        try:
            if all(file_sha256(out / name) == sha for name, sha in zip(row.files, row.sha256)):
                keep[row.id] = row._replace(model=item.model)    # (the file may have moved: same content)
        except OSError:                          # a file deleted since: made again
            continue
    return keep
