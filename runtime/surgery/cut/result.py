"""What a cut returns with its bookkeeping."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...animation.rig import Rig


#: values of ``CutResult.sources``: vertices created on crossed edges, and cap vertices
NEW_VERTEX, CAP_VERTEX = -1, -2


@dataclass(frozen=True, eq=False)
class CutResult:
    """A cut with the bookkeeping that relates the halves to the input (``cut_details``).

    Parameters
    ----------
    positive, negative : Rig
        The parts with signed distance d > 0 and d < 0 (on-plane vertices in both).
    sources : tuple of 2 (n_half,) int64
        Per half, the input vertex of each output vertex: ``NEW_VERTEX`` (-1) for a vertex made on
        a crossed edge, ``CAP_VERTEX`` (-2) for a cap vertex.
    edge_vertices : (k, 2) int64
        The input vertices (a, b) of the edge of each new vertex.
    edge_t : (k,) float64
        Its parameter: the cut-space position is (1 − t) x_a + t x_b.
    new_positions : (k, 3) float64
        The new vertices in the space that was cut (rest, or posed).
    first_new : tuple of 2 int
        Index of the first new vertex in each half (new vertex j is row ``first_new[h] + j``).
    plane : (4,) float64
        The dual plane n̂ + d e∞ that was cut with.
    tolerance : float
        The on-plane tolerance used (absolute, in cut-space units).
    residual : float
        The largest ``|skinned new vertex − its posed target|`` (0 for a rest cut).

    Examples
    --------
    >>> result = cgaskin.cut_details(cgaskin.capsule_arm(), [1, 0, 0], [1.55, 0, 0])
    >>> result.first_new, result.plane
    ((337, 353), array([1.  , 0.  , 0.  , 1.55]))
    """

    positive: Rig
    negative: Rig
    sources: tuple
    edge_vertices: np.ndarray
    edge_t: np.ndarray
    new_positions: np.ndarray
    first_new: tuple
    plane: np.ndarray
    tolerance: float
    residual: float
