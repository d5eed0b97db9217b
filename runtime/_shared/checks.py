"""Argument checks shared by the public functions: turn bad input into a ``InvalidInputError`` that
names the argument, before any numba kernel sees it."""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import InvalidInputError


def float_array(value, name: str, last: int | None = None, ndim: int | None = None) -> np.ndarray:
    """A finite float64 array (a copy only when needed), with last axis ``last`` if given."""
    try:
        arr = np.asarray(value)
        kind = arr.dtype.kind
        if kind in "USO" and not _all_numbers(arr):
            # numpy would parse "2" as 2.0: a string where a number belongs is a mistake to report
            raise TypeError(f"{kind == 'O' and 'objects' or 'strings'} are not numbers")
        if kind != "c" and arr.dtype != np.float64:
            arr = arr.astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be numeric, got {type(value).__name__}: {exc}") from None
    if arr.dtype.kind == "c":           # numpy would drop the imaginary part with a mere warning
        raise InvalidInputError(f"{name} must be real, got complex values")
    if last is not None and (arr.ndim == 0 or arr.shape[-1] != last):
        raise InvalidInputError(f"{name} must have shape (..., {last}), got {arr.shape}")
    if ndim is not None and arr.ndim != ndim:
        raise InvalidInputError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    # a finite sum is the cheap proof (these checks run on every call); only an overflowing sum of
    # finite values reaches the elementwise test without a culprit
    if not math.isfinite(arr.sum()) and not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise InvalidInputError(f"{name} holds a non-finite value (NaN or inf) at index {tuple(bad.tolist())}")
    return arr


def _all_numbers(arr) -> bool:
    """Whether an object array holds only numbers (not strings, not None)."""
    return arr.dtype.kind == "O" and all(isinstance(x, numbers.Real) for x in arr.flat)


def real_number(value, name: str) -> float:
    """A finite float from a real number (not a string, not a bool)."""
    if type(value) is not float and (isinstance(value, (bool, np.bool_))
                                     or not isinstance(value, numbers.Real)):
        raise InvalidInputError(f"{name} must be a real number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InvalidInputError(f"{name} must be finite, got {value}")
    return value


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


def item_index(value, count: int, what: str, has: str) -> int | None:
    """``value`` as an index into ``count`` items (clips, skeleton nodes) when it is an integer, else
    None (a name, for the caller to look up). One rule for every index a user gives: an int or numpy
    integer in [0, count). A bool is refused (``True`` is not clip 1), and so is a negative index
    (-1 marks a root in a skeleton's parents; it is not "the last node"). ``has`` ends the range
    error, e.g. "the rig has 2 clips"."""
    if isinstance(value, (bool, np.bool_)):
        raise InvalidInputError(f"{what} must be a name or an index in [0, {count}), got {value!r} (a bool)")
    if not isinstance(value, (int, np.integer)):
        return None
    if not 0 <= value < count:
        raise InvalidInputError(f"{what} index {value} out of range [0, {count}): {has}")
    return int(value)
