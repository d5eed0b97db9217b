"""Versors to and from the clifford package's ``g3c`` multivectors (clifford is a test and oracle
dependency: imported on first use). Public through ``cgaskin.versor``.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array
from ..errors import InvalidInputError
from ..generated.layout import VERSOR_BLADES, VERSOR_SIZE


def _clifford_basis():
    from clifford import g3c
    e1, e2, e3, einf, eo = g3c.e1, g3c.e2, g3c.e3, g3c.einf, g3c.eo
    vectors = {"1": e1, "2": e2, "3": e3, "∞": einf, "0": eo}
    blades = []
    for name in VERSOR_BLADES:
        blade = 1.0 + 0 * e1
        if name != "1":
            for ch in name[1:]:
                blade = blade ^ vectors[ch]
        blades.append(blade)
    return g3c, blades


def to_clifford(v):
    """The ``clifford.g3c`` multivector equal to a versor (a list of them for a batch).

    Parameters
    ----------
    v : (12,) or (..., 12) array_like
        Coefficients on ``VERSOR_BLADES``.

    Returns
    -------
    clifford.MultiVector or list of clifford.MultiVector

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], np.pi / 2)
    >>> print(cgaskin.versor.to_clifford(R))                   # doctest: +SKIP
    0.70711 - (0.70711^e12)
    """
    _, blades = _clifford_basis()
    arr = float_array(v, "versor", VERSOR_SIZE)
    if arr.ndim == 1:
        return sum((c * b for c, b in zip(arr, blades)), 0 * blades[0])
    return [to_clifford(row) for row in arr.reshape(-1, VERSOR_SIZE)]


def from_clifford(mv, tolerance: float = 1e-9) -> np.ndarray:
    """The versor array of a ``clifford.g3c`` multivector.

    Parameters
    ----------
    mv : clifford.MultiVector
        A multivector of ``clifford.g3c`` on the 12 versor blades.
    tolerance : float, optional
        Relative size of the parts on other blades that is still taken as rounding.

    Returns
    -------
    (12,) float64
        Coefficients on ``VERSOR_BLADES``.

    Raises
    ------
    InvalidInputError
        The multivector has parts on other blades.

    Examples
    --------
    >>> R = cgaskin.versor.rotor([0, 0, 1], np.pi / 2)
    >>> np.allclose(cgaskin.versor.from_clifford(cgaskin.versor.to_clifford(R)), R)   # doctest: +SKIP
    True
    """
    _, blades = _clifford_basis()
    basis = np.stack([b.value for b in blades], axis=1)          # (32, 12)
    coeffs, *_ = np.linalg.lstsq(basis, mv.value, rcond=None)
    rest = mv.value - basis @ coeffs
    if np.max(np.abs(rest)) > tolerance * max(1.0, np.max(np.abs(mv.value))):
        raise InvalidInputError("the multivector has components outside the 12-blade versor type")
    return coeffs
