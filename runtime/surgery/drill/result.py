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
    """A drill with the bookkeeping that relates its rig to the input (``drill_details``).

    Parameters
    ----------
    rig : Rig
        The drilled rig.
    sources : (n_out,) int64
        The input vertex of each output vertex, ``NEW_VERTEX`` (-1) for a vertex the drill made.
    first_new : int
        The first new vertex: new vertex j is output vertex ``first_new + j``.
    rim : (r,) int64
        The output vertices on the bit's surface.
    new_positions : (k, 3) float64
        The new vertices in the space that was drilled (rest, or posed).
    removed_faces : int
        The input faces (after refinement) taken away or cut by the bit.
    replaced : (t,) int64
        The input faces the drill replaced (split, cut or taken away; ascending): the result's faces
        are the other input faces, in their order, then the faces made in their place.
    made_in : (f,) int64
        For each face made (the last f of the result's), the input face it lies in (-1: a wall's).
    wall_faces : int
        The walls' faces: the last ``wall_faces`` rows of ``rig.faces``.
    open_rims : int
        Rims that run into an open boundary of the mesh (``wall=True``): chains, not loops, which no
        wall joins (the hole stays open there; ``OpenRimWarning``).
    unclosed_edges : int
        Edges on the bit's surface that the walls leave without exactly two faces, besides the
        chains' (``wall=True``; ``OpenRimWarning``): 0 for closed shells of either winding, disjoint
        or not; a hole through an open surface, or a surface wound against its neighbours around a
        blind hole, leaves its rim's edges.
    bit : Bit
        The bit: its travel and radius.
    tolerance : float
        The on-surface tolerance (absolute, in the drilled space's units).
    residual : float
        The largest ``|skinned new vertex - where it was made|`` (0 for a drill at rest).
    _describe : callable
        Makes ``new``, the first time it is asked for (private: ``assemble.py`` gives it).

    Examples
    --------
    >>> result = cgaskin.drill_details(cgaskin.capsule_arm(), [1, 0, -1], [1, 0, 1], 0.1)
    >>> result.rig.n_vertices, result.first_new, result.new_positions.shape
    (1278, 680, (598, 3))
    >>> int((result.sources == -1).sum()), result.wall_faces, result.open_rims, result.unclosed_edges
    (598, 332, 0, 0)
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
        """The input vertices each new vertex lies between and its coefficients there (``NewVertices``).

        Made when first asked for: the drill itself blends each new vertex from the two vertices it
        was made between (``patch.row_skins``).
        """
        return self._describe()
