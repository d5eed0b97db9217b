"""Read-only arrays for the immutable data model (``Rig``, ``Skeleton``), and the kernels' view of them.

A rig's values are cached per rig (welded topology, BVH, bone influences: ``_shared.cache``), so an
array edited in place would leave them stale: the arrays a rig holds are read-only views
(``writeable=False``) of buffers that the rig alone owns (copies of what its maker passed, so the
maker's arrays stay writeable and unchanged).

numba types a read-only array apart from a writeable one and compiles a second variant of a kernel
for it (and ``cgaskin.precompile`` lists the writeable ones). Kernels that only read a rig's arrays
get the writeable buffer behind them (``kernel_array``): the same type as every other caller's, so
one compiled variant serves all.
"""
from __future__ import annotations

import numpy as np

from .memory import is_recycled

__all__ = ["frozen", "kernel_array", "FrozenDict"]


def frozen(array: np.ndarray) -> np.ndarray:
    """A read-only C-contiguous view of ``array``, which must be a fresh array nobody else holds (it
    is the buffer behind the view; copied first when it is itself a view, other than a recycled output
    array on its own block, or not C-contiguous)."""
    if (array.base is not None and not is_recycled(array)) or not array.flags.c_contiguous or not array.flags.writeable:
        array = np.array(array, order="C")
    view = array.view()
    view.flags.writeable = False
    return view


def kernel_array(array: np.ndarray) -> np.ndarray:
    """The writeable buffer behind a ``frozen`` array (for compiled kernels that only read it), or
    ``array`` itself when it is not one."""
    # (a view's base is the array owning the memory: with the view's shape, strides and dtype it is
    # the same memory; a few attribute reads, as skinning calls this for every frame)
    base = array.base
    if (type(base) is np.ndarray and not array.flags.writeable and base.flags.writeable
            and base.shape == array.shape and base.strides == array.strides and base.dtype == array.dtype):
        return base
    return array


class FrozenDict(dict):
    """A dict that refuses changes (a rig's attributes: its arrays are ``frozen`` too). A dict still
    (``json``, ``{**d}``, ``==``, ``copy.deepcopy`` and pickle work; copies are plain dicts)."""

    def _read_only(self, *args, **kwargs):
        raise TypeError("a rig's attributes are read-only: make a new rig with "
                        "rig.with_mesh(..., attributes={...}) instead")

    __setitem__ = __delitem__ = __ior__ = _read_only
    clear = pop = popitem = setdefault = update = _read_only

    def __reduce__(self):
        return dict, (dict(self),)

    def copy(self) -> dict:
        return dict(self)
