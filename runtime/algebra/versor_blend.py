"""The logarithm and exponential of versors, and the blends built on them (linear and logarithmic).
Public through ``cgaskin.versor``.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array
from ..errors import InvalidInputError
from ..generated import kernels as K
from ..generated.layout import LOG_SIZE, VERSOR_SIZE
from .versor_products import _rows, _versor_arg, compose, inverse, normalise


def log(v) -> np.ndarray:
    """The logarithm of versors: bivectors Λ with exp(Λ) == V (up to sign).

    Parameters
    ----------
    v : (..., 12) array_like
        Similarity versors.

    Returns
    -------
    (..., 7) float64
        Coefficients on ``LOG_BLADES`` (e12, e13, e23, e1∞, e2∞, e3∞, e∞0).

    Examples
    --------
    >>> cgaskin.versor.log(cgaskin.versor.rotor([0, 0, 1], np.pi / 2)).round(3) + 0.0   # -θ/2 e12
    array([-0.785,  0.   ,  0.   ,  0.   ,  0.   ,  0.   ,  0.   ])
    """
    return _rows(K.versor_log_batch, LOG_SIZE, (_versor_arg(v), True))


def exp(bivector) -> np.ndarray:
    """The versor exp(Λ_M) exp(λ e∞0) of bivectors on ``LOG_BLADES`` (the inverse of ``log``).

    Parameters
    ----------
    bivector : (..., 7) array_like
        Coefficients on ``LOG_BLADES``.

    Returns
    -------
    (..., 12) float64

    Raises
    ------
    InvalidInputError
        A scale (or translation) too large for a finite versor.

    Examples
    --------
    >>> T = cgaskin.versor.exp([0, 0, 0, -1.0, 0, 0, 0])       # -t/2 e1∞: the translator by t = 2 e1
    >>> cgaskin.versor.apply(T, [0, 0, 0])
    array([2., 0., 0.])
    """
    out = _rows(K.versor_exp_batch, VERSOR_SIZE, (float_array(bivector, "bivector", LOG_SIZE), True))
    if not np.isfinite(out).all():
        raise InvalidInputError("exp overflows float64: the bivector's scale coefficient (or its "
                                "translation) is too large for a finite versor")
    return out


def _blend_args(versors, weights):
    versors = _versor_arg(versors, "versors")
    weights = float_array(weights, "weights")
    if versors.ndim < 2 or weights.shape != versors.shape[:-1]:
        raise InvalidInputError(f"weights must have shape {versors.shape[:-1]} (one per versor), "
                                f"got {weights.shape}")
    # V and −V are the same transformation: align every versor with the first one (antipodality)
    sign = np.where(np.sum(versors[..., :1, :4] * versors[..., :4], axis=-1) < 0, -1.0, 1.0)
    return versors * sign[..., None], weights


def blend_linear(versors, weights) -> np.ndarray:
    """The normalised weighted sum of versors (each aligned with the first: V and -V are one).

    Parameters
    ----------
    versors : (..., k, 12) array_like
        The versors to blend.
    weights : (..., k) array_like
        One weight per versor.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> v = cgaskin.versor
    >>> halfway = v.blend_linear([v.identity(), v.translator([1, 2, 3])], [0.5, 0.5])
    >>> v.apply(halfway, [0, 0, 0])
    array([0.5, 1. , 1.5])
    """
    versors, weights = _blend_args(versors, weights)
    return normalise(np.einsum("...k,...kc->...c", weights, versors))


def blend_log(versors, weights) -> np.ndarray:
    """The logarithmic blend P exp(Σ_i w_i log(P⁻¹ V_i)), P the versor of largest weight.

    Two versors interpolate along the shortest screw motion between them (ScLERP, the short arc
    for rotations) with the scale interpolated geometrically; a weight of 1 returns its versor to
    rounding. For commuting versors (one rotation axis, pure translations, pure scales) it equals
    exp(Σ_i w_i log V_i).

    Parameters
    ----------
    versors : (..., k, 12) array_like
        The versors to blend.
    weights : (..., k) array_like
        One weight per versor, summing to 1.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> v = cgaskin.versor
    >>> halfway = v.blend_log([v.identity(), v.rotor([0, 0, 1], np.pi / 2)], [0.5, 0.5])
    >>> v.apply(halfway, [1, 0, 0]).round(3)                  # turned by 45 degrees
    array([0.707, 0.707, 0.   ])
    """
    versors, weights = _blend_args(versors, weights)
    pivot = np.take_along_axis(versors, np.argmax(weights, axis=-1)[..., None, None], axis=-2)
    # the sign of each versor that puts its rotor within a quarter turn of the pivot's (short arc)
    sign = np.where(np.sum(pivot[..., :4] * versors[..., :4], axis=-1) < 0, -1.0, 1.0)
    relative = compose(inverse(pivot), versors * sign[..., None])
    return compose(pivot[..., 0, :], exp(np.einsum("...k,...kc->...c", weights, log(relative))))
