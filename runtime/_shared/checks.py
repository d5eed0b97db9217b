"""Argument checks shared by the public functions: turn bad input into a ``InvalidInputError`` that
names the argument, before any numba kernel sees it."""
from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError


def float_array(value, name: str, last: int | None = None, ndim: int | None = None) -> np.ndarray:
    """A finite float64 array (a copy only when needed), with last axis ``last`` if given."""
    try:
        arr = np.asarray(value)
        if arr.dtype.kind != "c":
            arr = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be numeric, got {type(value).__name__}: {exc}") from None
    if arr.dtype.kind == "c":           # numpy would drop the imaginary part with a mere warning
        raise InvalidInputError(f"{name} must be real, got complex values")
    if last is not None and (arr.ndim == 0 or arr.shape[-1] != last):
        raise InvalidInputError(f"{name} must have shape (..., {last}), got {arr.shape}")
    if ndim is not None and arr.ndim != ndim:
        raise InvalidInputError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InvalidInputError(f"{name} holds a non-finite value (NaN or inf) at index {tuple(bad)}")
    return arr


def index_array(value, name: str, upper: int) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "iu":
        if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
            arr = arr.astype(np.int64)
        else:
            raise InvalidInputError(f"{name} must hold integer indices, got dtype {arr.dtype}")
    if arr.size and (arr.min() < 0 or arr.max() >= upper):
        raise InvalidInputError(f"{name} holds indices outside [0, {upper}): min {arr.min()}, max {arr.max()}")
    return arr
