"""What a cut returns with its bookkeeping."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...animation.rig import Rig


#: values of ``CutResult.sources``: vertices created on crossed edges, and cap vertices
NEW_VERTEX, CAP_VERTEX = -1, -2


@dataclass(frozen=True, eq=False)
class CutResult:
    """A cut with the bookkeeping that relates the halves to the input.

    positive, negative : Rig, the parts with d > 0 and d < 0 (on-plane vertices in both)
    sources : (Rig vertex -> input vertex) per half: ``(n_pos,)`` and ``(n_neg,)`` int64 arrays holding
        the input vertex of each output vertex, ``NEW_VERTEX`` (-1) for a vertex created on a crossed edge
        and ``CAP_VERTEX`` (-2) for a cap vertex
    edge_vertices : (k, 2) int64, the input vertices (a, b) of the edge of each new vertex
    edge_t : (k,) float64, its parameter: cut-space position (1 − t) x_a + t x_b
    new_positions : (k, 3) float64, the new vertices in the space that was cut (rest, or posed)
    first_new : (2,) int, index of the first new vertex in each half (new vertex j is row
        ``first_new[h] + j`` of half h)
    plane : (4,) float64, the dual plane n̂ + d e∞ that was cut with
    tolerance : float, the on-plane tolerance used (absolute, in cut-space units)
    residual : float, the largest |skinned new vertex − its posed target| (0 for a rest cut)
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
