"""float64 arrays through float32 glTF accessors, exactly: the rounding residuals that ``save_gltf``
writes beside a float32 accessor and the loader adds back (see export.py, "Precision").

A float64 array ``x`` is stored as its float32 rounding ``hi`` (what every reader uses) and, only
when ``hi`` differs from ``x``, two float32 residuals: ``lo`` the rounding of ``x - hi`` and ``lo2``
the rounding of what is left, so that ``(hi + lo) + lo2 == x`` in float64 (24 + 24 + 24 bits >= 53;
for 0 and |x| >= 2^-97 ~ 6e-30: below that the residuals underflow float32's subnormals).
The residuals are accessors named in the ``extras["cgaskin"]`` of the object that holds ``hi``
(a primitive, a skin, an animation sampler), which other readers ignore.
"""
from __future__ import annotations

import numpy as np

from ._gltf_constants import EXTRAS_KEY


def split(values: np.ndarray, high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, lo2) float32 with ``(high + lo) + lo2 == values``: the rounding residuals of the float64
    ``values`` beside their float32 rounding ``high`` (same shape)."""
    values = np.asarray(values, dtype=np.float64)
    rest = values - high.astype(np.float64)  # exact: the rounding error of a float32 rounding
    lo = rest.astype(np.float32)
    lo2 = (rest - lo.astype(np.float64)).astype(np.float32)
    return lo, lo2


def with_residuals(f, owner, names, values: np.ndarray, where: str) -> np.ndarray:
    """``values`` (float64, read from the float32 accessor) plus the residuals named in
    ``owner.extras["cgaskin"]`` (accessor indices ``extras["cgaskin"][name]`` for ``name`` in
    ``names``, each finite floats of ``values``' shape): the float64 originals exactly; unchanged
    without them. ``f`` is the ``_GltfFile``; anything malformed raises its ModelFormatError."""
    extras = getattr(owner, "extras", None)
    ours = extras.get(EXTRAS_KEY) if isinstance(extras, dict) else None
    if not isinstance(ours, dict):
        return values
    for name in names:
        if name not in ours:
            continue
        index = ours[name]
        what = f"{where} extras.{EXTRAS_KEY}.{name}"
        if isinstance(index, bool) or not isinstance(index, int):
            raise f.error(f"{what} must be an accessor index, got {index!r}")
        residual = f.accessor(index, what)
        if residual.shape != values.shape or residual.dtype != np.float64 or not np.isfinite(residual).all():
            raise f.error(f"{what} must be finite floats shaped like {name.rsplit('_', 1)[0]} "
                          f"{values.shape}, got {residual.dtype} {residual.shape}")
        values = values + residual
    return values
