"""What the target tests (tests/targets) run every printer on: the built-in catalogue's kernels and a
user catalogue's, their numba results as the reference, and hypothesis strategies for their inputs."""
from __future__ import annotations

import functools
import importlib.util
import sys

import numpy as np
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tests.helpers.catalogues import README_CATALOGUE


@functools.lru_cache(maxsize=None)
def builtin_kernels():
    """The built-in catalogue's scalar ``Kernel`` IRs (what generated/kernels.py prints) and the
    numba module that runs them."""
    from cgaskin.codegen import catalogue
    from cgaskin.generated import kernels as module
    return tuple(make() for make in catalogue.KERNELS), module


@functools.lru_cache(maxsize=None)
def user_kernels(tmp_dir):
    """The README's example catalogue (a user's kernels: Point inputs, a uniform Versor): its scalar
    Kernel IRs, their uniform inputs, and its numba module built into ``tmp_dir``."""
    from pathlib import Path
    from cgaskin.codegen.catalogue_build import build_catalogue, compile_kernel, load_catalogue
    Path(tmp_dir).mkdir(parents=True, exist_ok=True)
    path = Path(tmp_dir) / "userkernels.py"
    path.write_text(README_CATALOGUE)
    specs, _ = load_catalogue(path)
    compiled = [compile_kernel(s) for s in specs]
    build_catalogue(path, Path(tmp_dir) / "out", log=lambda *_: None)
    spec = importlib.util.spec_from_file_location("userkernels_numba", Path(tmp_dir) / "out" / "userkernels.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return tuple(c.kernel for c in compiled), {c.spec.name: c.uniform for c in compiled}, module


def input_arrays(kernel, rows: int, magnitude: float = 10.0):
    """A hypothesis strategy of the kernel's inputs for ``rows`` rows: one float64 array per input,
    (rows, size) or (rows,) for scalars, entries in [-magnitude, magnitude]."""
    elements = st.floats(-magnitude, magnitude, allow_nan=False, width=64)
    return st.tuples(*(hnp.arrays(np.float64, (rows,) if i.kind == "scalar" else (rows, len(i.symbols)),
                                  elements=elements) for i in kernel.inputs))


def reference(module, kernel, inputs):
    """(rows, outputs) float64: the numba scalar kernel ``module.<name>`` on every row."""
    fn = getattr(module, kernel.name)
    rows = len(inputs[0])
    out = np.empty((rows, len(kernel.outputs)))
    with np.errstate(all="ignore"):
        for r in range(rows):
            out[r] = np.asarray(fn(*(a[r] for a in inputs)), dtype=np.float64).reshape(-1)
    return out
