"""What a drill returns with its rig (``drill_details``)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

from ...animation.rig import Rig
from ..new_vertices import NewVertices
from .bit import Bit

#: ``DrillResult.sources`` of a vertex the drill made
NEW_VERTEX = -1


@dataclass(frozen=True, eq=False)
class DrillResult:
    """A drill with its bookkeeping.

    rig : Rig, the drilled rig
    sources : (n_out,) int64, the input vertex of each output vertex, ``NEW_VERTEX`` for a new one
    first_new : int, the first new vertex (new vertex j is output vertex ``first_new + j``)
    rim : (r,) int64, the output vertices on the bit's surface
    new_positions : (k, 3) float64, the new vertices in the space that was drilled (rest, or posed)
    removed_faces : int, input faces (after refinement) taken away or cut by the bit
    replaced : (t,) int64, the input faces the drill replaced (split, cut or taken away; ascending): the
        result's faces are the other input faces, in their order, then the faces made in their place
    made_in : (k,) int64, for each face made (the last k of the result's), the input face it lies in
        (-1: a wall's)
    wall_faces : int, the walls' faces: the last ``wall_faces`` rows of ``rig.faces``
    open_rims : int, rims that run into an open boundary of the mesh (``wall=True``): chains, not loops,
        which no wall joins (the hole stays open there; ``OpenRimWarning``)
    unclosed_edges : int, edges on the bit's surface that the walls leave without exactly two faces,
        besides the chains' (``wall=True``; ``OpenRimWarning``): 0 for closed shells of either winding,
        disjoint or not; a hole through an open surface, or a surface wound against its neighbours
        around a blind hole, leaves its rim's edges
    bit : Bit ; tolerance : float, the on-surface tolerance (absolute) ; residual : float, the largest
        |skinned new vertex - where it was made| (0 for a drill at rest)
    new : NewVertices, the input vertices each new vertex lies between and its coefficients there (made
        when first asked: the drill itself blends each new vertex from the two vertices it was made
        between, ``patch.row_skins``)
    """

    rig: Rig
    sources: np.ndarray
    first_new: int
    rim: np.ndarray
    new_positions: np.ndarray
    removed_faces: int
    replaced: np.ndarray
    made_in: np.ndarray
    wall_faces: int
    open_rims: int
    unclosed_edges: int
    bit: Bit
    tolerance: float
    residual: float
    _describe: Callable[[], NewVertices]

    @cached_property
    def new(self) -> NewVertices:
        return self._describe()
