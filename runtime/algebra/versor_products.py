"""Versor products over the generated kernels: the batched runner and argument checks every function
of ``cgaskin.versor`` uses, then the products (compose, reverse, inverse, normalise), the versors'
matrices and the transform of points. Public through ``cgaskin.versor``.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array
from .._shared.jit import F2, F1r, F2r, precompiled
from ..errors import InvalidInputError
from ..generated import kernels as K
from ..generated.layout import VERSOR_SIZE
from ..tolerances import tol

# the generated kernels the versor functions call, with the argument types ``_rows`` gives them
precompiled(K.versor_translator_batch, (F2r, F2), cost=0.3)
precompiled(K.versor_rotor_batch, (F2r, F1r, F2), cost=0.2)
precompiled(K.versor_rotor_quaternion_batch, (F2r, F2), cost=0.1)
precompiled(K.versor_dilator_batch, (F1r, F2), cost=0.3)
precompiled(K.gp_versor_versor_batch, (F2r, F2r, F2), cost=0.7)
precompiled(K.versor_to_affine_batch, (F2r, F2), cost=0.4)
precompiled(K.versor_residual_batch, (F2r, F2), cost=0.2)
precompiled(K.reverse_versor_batch, (F2r, F2), cost=0.2)
precompiled(K.versor_log_batch, (F2r, F2), cost=0.5)
precompiled(K.versor_exp_batch, (F2r, F2), cost=0.4)
precompiled(K.inverse_versor_batch, (F2r, F2), cost=0.3)
precompiled(K.versor_normalise_batch, (F2r, F2), cost=0.3)
precompiled(K.versor_from_matrix_batch, (F2r, F2), cost=0.4)
precompiled(K.affine_point_batch, (F2r, F2r, F2), cost=0.2)
# compiled inside the batch kernels above; listed so that one process owns each cache index
precompiled(K.reverse_versor, (F1r,), cost=0.2)
precompiled(K.versor_log, (F1r,), cost=0.4)
precompiled(K.versor_exp, (F1r,), cost=0.2)

VERSOR_TOLERANCE = tol.versor        # relative residual of V Ṽ beyond which an array is not a versor


def _rows(kernel_batch, n_out, *arrays):
    """Run a generated ``_batch`` kernel over broadcast leading axes; returns (..., n_out)."""
    shapes = [a.shape[:-1] if is_vector else a.shape for a, is_vector in arrays]
    try:
        lead = np.broadcast_shapes(*shapes)
    except ValueError:
        raise InvalidInputError(f"the arguments' leading axes {shapes} do not broadcast together") from None
    flat = []
    for a, is_vector in arrays:
        if is_vector:
            a = np.ascontiguousarray(np.broadcast_to(a, lead + a.shape[-1:])).reshape(-1, a.shape[-1])
        else:
            a = np.ascontiguousarray(np.broadcast_to(a, lead)).reshape(-1)
        # read-only views always (broadcasting gives some, copies not): one compiled kernel per type
        a = a.view()
        a.flags.writeable = False
        flat.append(a)
    n = int(np.prod(lead, dtype=np.int64))
    out = np.empty((n, n_out))
    if n:
        kernel_batch(*flat, out)
    return out.reshape(lead + (n_out,))


def _versor_test(arr):
    """(residual, scalar, ok): V Ṽ must be a positive scalar. Rounding alone leaves a non-scalar
    part of ~ε|V|² (large coefficients, e.g. translations of 1e4), so the residual is measured
    against the coefficients' squared size, not against ⟨V Ṽ⟩₀."""
    residual, norm = np.moveaxis(_rows(K.versor_residual_batch, 2, (arr, True)), -1, 0)
    size = np.sum(arr * arr, axis=-1)
    return residual, norm, (norm > 0) & (residual <= VERSOR_TOLERANCE * np.maximum(size, 1.0))


def _versor_arg(v, name="versor", check=True) -> np.ndarray:
    arr = float_array(v, name, last=VERSOR_SIZE)
    if check:
        residual, norm, ok = _versor_test(arr)
        bad = ~ok
        if np.any(bad):
            idx = tuple(np.argwhere(np.atleast_1d(bad))[0])
            raise InvalidInputError(
                f"{name} is not a similarity versor (V Ṽ must be a positive scalar; at index {idx} its "
                f"non-scalar part is {np.atleast_1d(residual)[idx]:.3g} against scalar "
                f"{np.atleast_1d(norm)[idx]:.3g}); build versors with motor/dilator/compose or "
                f"call normalise")
    return arr


def is_versor(v) -> np.ndarray:
    """Whether each array is a similarity versor: V Ṽ a positive scalar, within tolerance.

    Parameters
    ----------
    v : (..., 12) array_like
        Coefficients on ``VERSOR_BLADES``.

    Returns
    -------
    (...,) bool

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], 1.0)
    >>> cgaskin.versor.is_versor([R, R + np.eye(12)[11]])        # an e23∞0 part too many
    array([ True, False])
    """
    return _versor_test(float_array(v, "versor", last=VERSOR_SIZE))[2]


def compose(*versors) -> np.ndarray:
    """The geometric product V1 V2 ... Vn: applies Vn first, V1 last (like matrices).

    Parameters
    ----------
    *versors : (..., 12) array_like
        At least one; their leading axes broadcast together.

    Returns
    -------
    (..., 12) float64
        A new array (never one of the caller's).

    Examples
    --------
    >>> v = cgaskin.versor
    >>> turn_then_move = v.compose(v.translator([1, 2, 3]), v.rotor([0, 0, 1], np.pi / 2))
    >>> v.apply(turn_then_move, [1, 0, 0]).round(3)
    array([1., 3., 3.])
    """
    if not versors:
        raise InvalidInputError("compose needs at least one versor")
    result = np.array(_versor_arg(versors[0], "versors[0]", check=False))    # never the caller's array
    for i, v in enumerate(versors[1:], 1):
        result = _rows(K.gp_versor_versor_batch, VERSOR_SIZE, (result, True),
                       (_versor_arg(v, f"versors[{i}]", check=False), True))
    return result


def reverse(v) -> np.ndarray:
    """The reverse Ṽ: each blade's vectors in reverse order (the inverse of a unit versor).

    Parameters
    ----------
    v : (..., 12) array_like
        Versors.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], np.pi / 2)
    >>> cgaskin.versor.reverse(R)[:4].round(3) + 0.0           # the e12 part changes sign
    array([0.707, 0.707, 0.   , 0.   ])
    """
    return _rows(K.reverse_versor_batch, VERSOR_SIZE, (_versor_arg(v, check=False), True))


def inverse(v) -> np.ndarray:
    """V⁻¹ = Ṽ / (V Ṽ): undoes ``apply(V, ·)``.

    Parameters
    ----------
    v : (..., 12) array_like
        Similarity versors.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> v = cgaskin.versor
    >>> V = v.compose(v.translator([1, 2, 3]), v.dilator(2.0))
    >>> v.apply(v.inverse(V), v.apply(V, [1, 0, 0])).round(3)
    array([1., 0., 0.])
    """
    return _rows(K.inverse_versor_batch, VERSOR_SIZE, (_versor_arg(v), True))


def normalise(v) -> np.ndarray:
    """The nearest similarity versor T R D with V Ṽ = 1 (after blending, for example).

    Parameters
    ----------
    v : (..., 12) array_like
        Near-versors: the rotor part must be larger than the e∞0 part, else InvalidInputError.

    Returns
    -------
    (..., 12) float64

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], np.pi / 2)
    >>> cgaskin.versor.normalise(2 * R)[:4].round(3) + 0.0
    array([ 0.707, -0.707,  0.   ,  0.   ])
    """
    arr = _versor_arg(v, check=False)
    rot = np.linalg.norm(arr[..., :4], axis=-1)
    dil = np.linalg.norm(arr[..., 8:], axis=-1)
    if np.any(rot <= dil):
        raise InvalidInputError("cannot normalise: the rotor part is not larger than the e∞0 part "
                                "(no positive scale matches); the input is not near a versor")
    return _rows(K.versor_normalise_batch, VERSOR_SIZE, (arr, True))


def to_affine(v) -> np.ndarray:
    """The affine maps [s R | t] of versors: apply(V, x) = A[:, :3] x + A[:, 3].

    Parameters
    ----------
    v : (..., 12) array_like
        Similarity versors.

    Returns
    -------
    (..., 3, 4) float64

    Examples
    --------
    >>> cgaskin.versor.to_affine(cgaskin.versor.motor([0, 0, 1], np.pi / 2, [1, 2, 3])).round(3) + 0.0
    array([[ 0., -1.,  0.,  1.],
           [ 1.,  0.,  0.,  2.],
           [ 0.,  0.,  1.,  3.]])
    """
    return _rows(K.versor_to_affine_batch, 12, (_versor_arg(v), True)).reshape(
        np.shape(v)[:-1] + (3, 4))


def to_matrix(v) -> np.ndarray:
    """The homogeneous 4x4 matrices of versors (``to_affine`` with the row 0 0 0 1).

    Parameters
    ----------
    v : (..., 12) array_like
        Similarity versors.

    Returns
    -------
    (..., 4, 4) float64

    Examples
    --------
    >>> cgaskin.versor.to_matrix(cgaskin.versor.translator([1, 2, 3]))[:, 3]
    array([1., 2., 3., 1.])
    """
    a = to_affine(v)
    m = np.zeros(a.shape[:-2] + (4, 4))
    m[..., :3, :] = a
    m[..., 3, 3] = 1.0
    return m


def apply(v, points) -> np.ndarray:
    """Transform points by versors: down(V up(x) Ṽ).

    Parameters
    ----------
    v : (..., 12) array_like
        Similarity versors.
    points : (..., 3) array_like
        Points; their leading axes broadcast with the versors'.

    Returns
    -------
    (..., 3) float64

    Examples
    --------
    >>> cgaskin.versor.apply(cgaskin.versor.dilator(2.0), [[1, 2, 3], [0, 0, 1]])
    array([[2., 4., 6.],
           [0., 0., 2.]])
    """
    affine = _rows(K.versor_to_affine_batch, 12, (_versor_arg(v), True))
    return _rows(K.affine_point_batch, 3, (affine, True), (float_array(points, "points", 3), True))
