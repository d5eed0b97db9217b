"""Datasets of deformed, cut, torn and drilled rigs, made on Dask (``cgaskin batch``).

``run(spec, out)`` reads a TOML spec (``spec.py``), expands it into items with content-hash ids
(``items.py``), makes each item in a Dask task (``operate.py``) and records them in
``out/manifest.parquet`` (``manifest.py``). Importing this package does not import dask or pyarrow
(``pip install 'cgaskin[batch]'``): ``run`` does.
"""
from .items import Item, expand
from .manifest import read_manifest
from .operate import Row
from .run import Manifest, run
from .spec import Spec, load_spec, parse_spec

__all__ = ["run", "Manifest", "Row", "Item", "Spec", "load_spec", "parse_spec", "expand", "read_manifest"]
