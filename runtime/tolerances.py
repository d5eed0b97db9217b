"""The runtime's tolerances, in one frozen object (``cgaskin.tolerances.tol``).

Every value is relative: to the bounding-box diagonal of the mesh being operated on, to a matrix's
largest entry, or to 1 for quantities that are 1 by construction (weight sums, sines). Kernels get
them as arguments (numba freezes module globals at compile time, so a global would ignore a changed
value and a cached kernel would keep the old one).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Tolerances", "tol"]


@dataclass(frozen=True)
class Tolerances:
    """Relative tolerances, in one frozen object (``tol``): when a vertex is on a plane or an edge,
    an array a versor, a matrix a TRS. Each field's comment says what it bounds and why.

    Parameters
    ----------
    on_plane : float
        Cut: a vertex this close (times the diagonal) to the plane is on it.
    snap : float
        Tear: a vertex or a hit this close (times the diagonal) to the path is snapped to.
    placement : float
        Posed cut/tear: a new vertex farther (times the diagonal) from its posed target is reported.
    on_edge : float
        Tear: a point whose smallest barycentric coordinate is at most this lies on an edge.
    tip_reach : float
        Tear: a blade this close (times the diagonal) to the last slit's tip continues that slit.
    min_sine : float
        Tear: three points below this sine are too close to one line to define a plane.
    collinear_sine : float
        Caps: a loop's corner turning by a sine below this is straight.
    box_padding : float
        BVH: boxes grow by this times the mesh's extent.
    affine_row : float
        Inverse bind matrices: how far (absolute) the last row may be from (0, 0, 0, 1).
    weight_sum : float
        Weights: a row off 1 by more than this is renormalised with a warning.
    exact_weight_sum : float
        Weights: a row off 1 by at most this is left as it is.
    versor : float
        Versors: the relative residual of V Ṽ beyond which an array is not a versor.
    pose_change : float
        Clips from poses: a node whose local matrix changes by more than this is animated.
    trs_rebuild : float
        A matrix that its TRS rebuilds to within this is a TRS (else it has shear).
    trs_exact : float
        Skeletons: a stored TRS that reproduces its exact matrix to within this is exact.

    Examples
    --------
    >>> from cgaskin.tolerances import tol
    >>> tol.on_plane, tol.versor
    (1e-10, 1e-06)
    >>> import dataclasses
    >>> dataclasses.replace(tol, on_plane=1e-8).on_plane       # a new object: tol is frozen
    1e-08
    """

    #: cut: a vertex within this times the diagonal of the plane is on it (it goes to both halves)
    on_plane: float = 1e-10
    #: tear: a vertex within this times the diagonal of the tear plane is on it (the path goes
    #: through it), and a scalpel hit this close to a vertex (or to a plane/edge crossing) is that one.
    #: As large as the rounding of float32 data: a vertex stored on a symmetry plane lies 2e-9 of the
    #: diagonal off it once skinned through float32 bind matrices (Fox in its rest pose), and a plane
    #: passing that close beside a vertex would cut pieces of near-zero area around it
    snap: float = 1e-8
    #: posed cut/tear: a new vertex whose skinned rest position misses its posed target by more than
    #: this times the diagonal is reported (its blended transform is singular or nearly so)
    placement: float = 1e-9
    #: tear: a point whose smallest barycentric coordinate in a triangle is at most this lies on the
    #: edge opposite that corner (splitting the triangle in three there would leave one of zero area)
    on_edge: float = 1e-9
    #: tear: a blade at t_i that passes within this times the diagonal (or within the stroke's opening,
    #: when wider) of the tip of the slit the last stroke made starts there: it continues that slit,
    #: wherever the pose carried the tip since
    tip_reach: float = 1e-3
    #: tear: below this sine, three points are too close to one line to define the tear plane
    min_sine: float = 1e-6
    #: caps: a corner of a loop turning by a sine below this is straight (no ear: collinear loop
    #: vertices would make zero-area cap triangles)
    collinear_sine: float = 1e-9
    #: BVH: boxes grow by this times the mesh's extent, so that rounding never loses a hit on a face
    #: lying in a box's side
    box_padding: float = 1e-9
    #: inverse bind matrices: ``|last row - (0, 0, 0, 1)|`` beyond this (absolute) is not affine
    affine_row: float = 1e-6
    #: weights: a row whose sum is off 1 by more than this is renormalised with a warning
    weight_sum: float = 1e-6
    #: weights: a row off 1 by at most this is left as it is (a few float64 roundings)
    exact_weight_sum: float = 2e-15
    #: versors: relative residual of V Ṽ beyond which an array is not a versor
    versor: float = 1e-6
    #: clips from poses: a node whose local matrix differs from its rest matrix by more than this
    #: times its largest entry is animated
    pose_change: float = 1e-12
    #: clips from poses and node transforms: a matrix that its TRS decomposition rebuilds to within
    #: this times its largest entry is a TRS (else it has shear)
    trs_rebuild: float = 1e-9
    #: skeletons: a node's stored TRS that reproduces its exact matrix to this times its largest
    #: entry (at least 1) is exact
    trs_exact: float = 1e-12


#: the tolerances every function of cgaskin uses
tol = Tolerances()
