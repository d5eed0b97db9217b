"""Versors of CGA as float64 arrays: rotation, translation and uniform scale in one algebra.

A versor is an array of shape (..., 12): its coefficients on ``VERSOR_BLADES``
(1, e12, e13, e23, e1∞, e2∞, e3∞, e123∞, e∞0, e12∞0, e13∞0, e23∞0) in the null basis
(e∞ = e− + e+, e0 = (e− − e+)/2). Every function is batched over leading axes and calls only the
generated kernels. ``compose(a, b)`` applies b first (like matrices); a joint's local transform is
T R D. This module makes versors; the products (``versor_products.py``), logarithms and blends
(``versor_blend.py``) and the clifford interop (``versor_clifford.py``) are public here too.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array
from ..errors import InvalidInputError
from ..generated import kernels as K
from ..generated.layout import LOG_BLADES, VERSOR_BLADES, VERSOR_SIZE
from .versor_blend import blend_linear, blend_log, exp, log
from .versor_clifford import from_clifford, to_clifford
# (VERSOR_TOLERANCE: the relative residual of V Ṽ beyond which an array is not a versor)
from .versor_products import (VERSOR_TOLERANCE, _rows, apply, compose, inverse, is_versor, normalise, reverse,
                              to_affine, to_matrix)

__all__ = ["VERSOR_BLADES", "LOG_BLADES", "identity", "translator", "rotor", "rotor_from_quaternion",
           "dilator", "motor", "compose", "reverse", "inverse", "normalise", "apply", "to_matrix",
           "to_affine", "from_matrix", "log", "exp", "blend_linear", "blend_log", "to_clifford",
           "from_clifford", "is_versor"]

#: dilation factors a versor holds: V Ṽ of a dilator cancels terms of the size of the scale, so
#: beyond about 1e15 (or below 1e-16) float64 cannot hold one at all; 1e±12 keeps a margin
SCALE_RANGE = (1e-12, 1e12)


def identity(shape=()) -> np.ndarray:
    """The identity versor (1), or an array of them.

    Parameters
    ----------
    shape : int or tuple of int, optional
        The leading axes (default: one versor).

    Returns
    -------
    (..., 12) float64
        ``shape`` leading axes.

    Examples
    --------
    >>> cgaskin.versor.identity()[:4], cgaskin.versor.identity((2, 3)).shape
    (array([1., 0., 0., 0.]), (2, 3, 12))
    """
    v = np.zeros(tuple(np.atleast_1d(shape)) + (VERSOR_SIZE,) if shape != () else (VERSOR_SIZE,))
    v[..., 0] = 1.0
    return v


def translator(translation) -> np.ndarray:
    """The translator T = 1 − ½ t e∞: moves points by t.

    Parameters
    ----------
    translation : (..., 3) array_like
        The translations t.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> T = cgaskin.versor.translator([1, 2, 3])
    >>> T[[0, 4, 5, 6]]                                         # 1, e1∞, e2∞, e3∞
    array([ 1. , -0.5, -1. , -1.5])
    >>> cgaskin.versor.apply(T, [0, 0, 0])
    array([1., 2., 3.])
    """
    return _rows(K.versor_translator_batch, VERSOR_SIZE, (float_array(translation, "translation", 3), True))


def rotor(axis, angle) -> np.ndarray:
    """The rotor of a rotation about an axis through the origin.

    Parameters
    ----------
    axis : (..., 3) array_like
        Rotation axes, any nonzero length (zero: InvalidInputError).
    angle : float or (...,) array_like
        Radians, right-handed about ``axis``.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], np.pi / 2)
    >>> cgaskin.versor.apply(R, [1, 0, 0]).round(3)
    array([0., 1., 0.])
    """
    axis = float_array(axis, "axis", 3)
    angle = float_array(angle, "angle")
    if np.any(np.linalg.norm(axis, axis=-1) == 0):
        raise InvalidInputError("axis has zero length: a rotation needs a direction")
    return _rows(K.versor_rotor_batch, VERSOR_SIZE, (axis, True), (angle, False))


def rotor_from_quaternion(q) -> np.ndarray:
    """The rotor of unit quaternions in (x, y, z, w) order (glTF's).

    Parameters
    ----------
    q : (..., 4) array_like
        Quaternions, any nonzero length.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> quarter_turn = [0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)]     # about z
    >>> cgaskin.versor.apply(cgaskin.versor.rotor_from_quaternion(quarter_turn), [1, 0, 0]).round(3)
    array([0., 1., 0.])
    """
    q = float_array(q, "quaternion", 4)
    if np.any(np.linalg.norm(q, axis=-1) == 0):
        raise InvalidInputError("quaternion has zero length")
    return _rows(K.versor_rotor_quaternion_batch, VERSOR_SIZE, (q, True))


def dilator(scale) -> np.ndarray:
    """The dilator D: uniform scale about the origin, apply(dilator(s), x) == s * x.

    Parameters
    ----------
    scale : float or (...,) array_like
        Factors in ``SCALE_RANGE`` ([1e-12, 1e12]), else InvalidInputError.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> cgaskin.versor.apply(cgaskin.versor.dilator(2.0), [1, 2, 3])
    array([2., 4., 6.])
    """
    scale = float_array(scale, "scale")
    low, high = SCALE_RANGE
    outside = (scale < low) | (scale > high)
    if np.any(outside):
        raise InvalidInputError(f"scale must lie in [{low:g}, {high:g}] (a dilation float64 can hold), "
                                f"got {float(scale[outside].flat[0])!r}")
    return _rows(K.versor_dilator_batch, VERSOR_SIZE, (scale, False))


def motor(axis=(0.0, 0.0, 1.0), angle=0.0, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The rigid motion T(translation) R(axis, angle): rotate about the origin, then translate.

    Parameters
    ----------
    axis : (..., 3) array_like, optional
        Rotation axes (default: z).
    angle : float or (...,) array_like, optional
        Radians (default: 0).
    translation : (..., 3) array_like, optional
        Translations (default: none).

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> M = cgaskin.versor.motor([0, 0, 1], np.pi / 2, [0, 0, 1])
    >>> cgaskin.versor.apply(M, [1, 0, 0]).round(3)
    array([0., 1., 1.])
    """
    return compose(translator(translation), rotor(axis, angle))


def from_matrix(m, tolerance: float = 1e-6) -> np.ndarray:
    """The versors of 4x4 matrices that are rotation + translation + uniform scale.

    Parameters
    ----------
    m : (..., 4, 4) array_like
        Homogeneous matrices acting on column vectors.
    tolerance : float, optional
        How far the linear part may be from a positive multiple of a rotation.

    Returns
    -------
    (..., 12) float64

    Raises
    ------
    InvalidInputError
        Shear, non-uniform scale, reflection or a last row other than 0 0 0 1: those are not
        similarities (keep them as matrices; see ``cgaskin.skin_affine``).

    Examples
    --------
    >>> m = np.diag([2.0, 2.0, 2.0, 1.0])
    >>> m[:3, 3] = [1, 2, 3]                                    # scale by 2, then move
    >>> cgaskin.versor.apply(cgaskin.versor.from_matrix(m), [1, 1, 1])
    array([3., 4., 5.])
    """
    m = float_array(m, "matrix", 4)
    if m.shape[-2:] != (4, 4):
        raise InvalidInputError(f"matrix must have shape (..., 4, 4), got {m.shape}")
    if not np.allclose(m[..., 3, :], [0, 0, 0, 1], atol=tolerance):
        raise InvalidInputError("matrix last row must be (0, 0, 0, 1)")
    lin = m[..., :3, :3]
    det = np.linalg.det(lin)
    gram = np.swapaxes(lin, -1, -2) @ lin
    s2 = np.cbrt(det)[..., None, None] ** 2
    if np.any(det <= 0) or np.any(np.abs(gram - s2 * np.eye(3)) > tolerance * np.maximum(s2, 1e-300)):
        raise InvalidInputError("matrix is not a similarity (rotation, translation, positive uniform "
                                "scale): it has shear, non-uniform scale or a reflection")
    return _rows(K.versor_from_matrix_batch, VERSOR_SIZE, (m.reshape(m.shape[:-2] + (16,)), True))
