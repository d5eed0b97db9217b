"""Cut a skinned mesh with a plane into two rigs.

``cut(rig, normal, point, pose=None, cap=False) -> (positive, negative)``

The plane is {x : n·(x − point) = 0}; ``positive`` is the part on the side the normal points to
(signed distance d > 0), ``negative`` the other part. Both keep the full skeleton and clips.

Steps (design.md section 4, "Cut (plane)"):

1. Positions to cut: the stored vertices (``pose=None``), or the skinned positions in ``pose`` (a
   posed cut; ``rig.rest_pose()`` cuts what a viewer shows at rest).
2. Signed distance of every welded vertex to the plane through the generated CGA kernel
   (``point_plane_distance``: up(x)·π); vertices within ``ON_PLANE_TOLERANCE`` times the bounding-box
   diagonal are *on* the plane and belong to both halves (no sliver faces, no duplicate vertices).
3. Faces entirely on one side (on-plane corners allowed) go to that side; a face lying in the plane goes
   to the side its normal points away from (so a closed part stays closed). A face with corners on
   both sides is split into one triangle and a quad (two triangles), or into two triangles when its
   third corner is on the plane; the winding is kept.
4. One new vertex per crossed *vertex edge* (attribute-split copies of a seam edge each get one, with
   their own NORMAL/TEXCOORD_0 interpolated by the edge parameter t), all copies at ONE position computed
   from the *welded* edge (generated ``segment_plane`` on the welded endpoints in a canonical order), so
   the halves have no cracks along seams. Weights: the two endpoint rows interpolated by t (up to 8
   influences), the 4 largest kept and renormalised.
5. A posed cut puts each new vertex on the plane *in that pose*: its posed position is the point of the
   posed edge, and its rest position solves B x = p for its own blended 3x4 map B = Σ w_k A_k (with the
   new weights), starting from the interpolated rest position and refined once; the residual is checked.
6. Each half keeps the original vertices it uses (in their original order, attributes and weights
   bit-for-bit) followed by the new vertices (same order in both halves).
7. ``cap=True`` closes each half: the boundary loops the cut created (welded boundary edges whose ends
   lie on the plane and that were not boundary edges before) are triangulated in the plane (ear clipping;
   a hole, a loop the mesh orients clockwise, is bridged into the smallest outer loop around it, so a
   hollow part gets an annulus), on cap vertices of their own (positions, joints and weights copied from
   the loop vertices, NORMAL along the outward plane normal, TEXCOORD_0 a planar projection), wound so
   that the cap faces outwards. A closed, consistently oriented input whose section does not intersect
   itself gives watertight halves; a self-intersecting section (a crumpled pose) gets overlapping caps.

Conventions and limits: vertices that no face uses are dropped. Attribute-split copies are assumed to
skin alike (same joints and weights, as files store them): a posed cut classifies and places a welded
vertex by its lowest-index copy. A rig is treated as immutable: its welded topology and checked arrays
are cached per rig (``cgaskin._shared.cache``), and its arrays are never written to.

A plane that misses the mesh (no face on one side) returns the whole rig (a copy) on the side it lies
on and an empty rig on the other, with a ``PlaneMissesMeshWarning``: ``(copy, empty)`` when the mesh
is on the positive side, ``(empty, copy)`` when it is on the negative side.
"""
from __future__ import annotations


import numpy as np

from ..._shared.cache import rig_cached
from ..._shared.checks import float_array
from ..._shared.jit import F1, f8, precompiled
from ..._shared.memory import Reusable
from ..._shared.warn import warn
from ...animation.rig import Rig
from ...animation.skinning import check_pose, skin_affine
from ...errors import InvalidInputError, PlacementWarning, PlaneMissesMeshWarning
from ...generated.kernels import plane_from_normal_distance
from ...tolerances import tol
from ..new_vertices import blend_weight_rows, interpolate_attribute, on_edges, place_in_rest
from ..surface import mesh_arrays
from ..topology import rig_topology
from .assemble import _split_arrays
from .cap import _cap
from .result import NEW_VERTEX, CutResult
from .split import _classify, scratch, split_halves

__all__ = ["cut", "cut_details", "CutResult", "PlaneMissesMeshWarning", "ON_PLANE_TOLERANCE",
           "PLACEMENT_TOLERANCE"]

precompiled(plane_from_normal_distance, (F1, f8), cost=0.1)

#: the tolerances a cut uses (``cgaskin.tolerances.tol``), under their former names
ON_PLANE_TOLERANCE, PLACEMENT_TOLERANCE = tol.on_plane, tol.placement


# ---- argument checks ----------------------------------------------------------------------------------
def _plane(normal, point) -> np.ndarray:
    n = float_array(normal, "normal", 3, ndim=1)
    p = float_array(point, "point", 3, ndim=1)
    scale = np.abs(n).max()
    if scale == 0.0:
        raise InvalidInputError("normal must not be the zero vector")
    n = n / scale                  # the kernel normalises; pre-scaling keeps n·n from under/overflowing
    return np.array(plane_from_normal_distance(n, float(n @ p)))


def _empty_like(rig, name) -> Rig:
    attributes = {k: np.empty((0,) + np.asarray(v).shape[1:], np.asarray(v).dtype)
                  for k, v in rig.attributes.items()}
    return Rig._of_checked(np.empty((0, 3)), np.empty((0, 3), np.int64), np.empty((0, 4), np.int64),
                          np.empty((0, 4)), rig.skeleton, rig.clips, attributes, name)


def _copy(rig, name) -> Rig:
    return Rig._of_checked(np.array(rig.vertices, dtype=np.float64), np.array(rig.faces), np.array(rig.joints),
                          np.array(rig.weights), rig.skeleton, rig.clips,
                          {k: np.array(v) for k, v in rig.attributes.items()}, name)


def cut_details(rig: Rig, normal, point, pose=None, cap: bool = False) -> CutResult:
    """``cut`` with the bookkeeping: which input vertex each output vertex comes from, the new
    vertices' edges and parameters, the plane and tolerances.

    Parameters
    ----------
    rig : Rig
        The model to cut.
    normal : (3,) float
        The plane's normal, any non-zero length.
    point : (3,) float
        A point of the plane.
    pose : Pose, optional
        Cut the mesh as posed in this pose (as ``cut``).
    cap : bool, optional
        Close each half with planar caps.

    Returns
    -------
    CutResult
        The halves and the bookkeeping.

    Examples
    --------
    >>> result = cgaskin.cut_details(cgaskin.capsule_arm(), [1, 0, 0], [1.55, 0, 0])
    >>> result.positive.n_vertices, result.negative.n_vertices, len(result.edge_t)
    (369, 385, 32)
    >>> int((result.sources[0] == -1).sum())              # NEW_VERTEX: made on a crossed edge
    32
    """
    return _cut(rig, normal, point, pose, cap, with_sources=True)


def _cut(rig: Rig, normal, point, pose, cap, with_sources: bool) -> CutResult:
    """``cut_details``; ``CutResult.sources`` is None unless ``with_sources`` (``cut`` does not return
    them: two arrays of the halves' vertex counts less to make)."""
    vertices, faces, joints, weights = mesh_arrays(rig)
    plane = _plane(normal, point)
    if not isinstance(cap, (bool, np.bool_)):
        raise InvalidInputError(f"cap must be True or False, got {cap!r}")
    affines = None
    if pose is None:
        positions = vertices
    else:
        affines = check_pose(rig, pose).bone_affines()
        positions = skin_affine(vertices, joints, weights, affines)
    topo = rig_topology(rig)

    # The working arrays are kept per rig: a cut repeated on the same rig finds their pages mapped.
    # ``split.pos_src`` and ``neg_src`` are rows of them, so they go back once the halves are made.
    reusable = rig_cached(rig, "cut.scratch", lambda _rig: Reusable(lambda: scratch(faces, topo)))
    work = reusable.take()
    on_plane, diag = _classify(plane, positions, topo.representative, topo.welded, tol.on_plane,
                               work.distance, work.welded_sign, work.sign)
    split = split_halves(plane, positions, faces, topo, work)
    if len(split.pos_faces) == 0 or len(split.neg_faces) == 0:
        in_plane = not work.welded_sign.any()
        reusable.give_back(work)
        return _missed(rig, len(split.pos_faces) > 0, in_plane, plane, on_plane)

    new = on_edges(split.new_lo, split.new_hi, split.new_t)
    new_joints, new_weights = blend_weight_rows(new.src, new.coef, joints, weights)
    new_rest, residual = split.new_point, 0.0
    if affines is not None:
        new_rest, residual = _placed(vertices, new, split.new_point, new_joints, new_weights, affines, diag)
    arrays = _split_arrays(rig, vertices, joints, weights, split.pos_src, split.neg_src, new, new_rest,
                           new_joints, new_weights)
    names = (f"{rig.name}_positive", f"{rig.name}_negative")
    halves = [Rig._of_checked(v, f, j, w, rig.skeleton, rig.clips, a, names[h])
              for h, ((v, j, w, a), f) in enumerate(zip(arrays, (split.pos_faces, split.neg_faces)))]
    sources = None
    if with_sources or cap:
        new_sources = np.full(len(split.new_lo), NEW_VERTEX, np.int64)
        sources = [np.concatenate([split.pos_src, new_sources]), np.concatenate([split.neg_src, new_sources])]
    first_new = (len(split.pos_src), len(split.neg_src))
    if cap:
        on_plane_input = work.sign == 0
        for h, kept in enumerate((split.pos_src, split.neg_src)):
            cut_positions = np.concatenate([positions[kept], split.new_point])
            halves[h], sources[h] = _cap(halves[h], sources[h], cut_positions, plane, on_plane_input, topo,
                                         outward=-1.0 if h == 0 else 1.0, affines=affines)
    reusable.give_back(work)
    return CutResult(halves[0], halves[1], None if sources is None else tuple(sources), new.src, split.new_t,
                     split.new_point, first_new, plane, on_plane, residual)


def _placed(vertices, new, targets, new_joints, new_weights, affines, diag):
    """Step 5: rest positions of the new vertices of a posed cut, and the largest placement residual
    (a ``PlacementWarning`` when some new vertex misses the plane)."""
    guess = interpolate_attribute("POSITION", vertices, new)
    rest, residuals = place_in_rest(targets, guess, new_joints, new_weights, affines)
    singular = ~np.isfinite(residuals)
    residual = float(residuals.max()) if len(residuals) else 0.0
    if residual > tol.placement * diag:
        missing = np.count_nonzero(residuals[~singular] > tol.placement * diag)
        warn(f"{int(singular.sum())} new vertices have a singular blended transform in this "
             f"pose and {missing} miss the plane by more than {tol.placement:g} of the "
             f"diagonal (largest {residual:.3g}); they keep their interpolated rest positions",
             PlacementWarning)
    return rest, residual


def _missed(rig, on_positive: bool, in_plane: bool, plane, on_plane) -> CutResult:
    """The plane misses the mesh: the whole rig (a copy) on its side, an empty rig on the other. A
    mesh lying in the plane goes to the side its faces point away from."""
    side, other = ("positive", "negative") if on_positive else ("negative", "positive")
    where = (f"the mesh lies in the plane, its faces facing the {other} side, so it is the {side} half"
             if in_plane else f"the mesh lies entirely on the {side} side")
    warn(f"the cutting plane does not cross the mesh of {rig.name!r}: {where}; the other half is empty",
         PlaneMissesMeshWarning)
    names = (f"{rig.name}_positive", f"{rig.name}_negative")
    whole, empty = _copy(rig, names[1 - on_positive]), _empty_like(rig, names[on_positive])
    everything = np.arange(rig.n_vertices, dtype=np.int64)
    nothing = np.empty(0, np.int64)
    halves = (whole, empty) if on_positive else (empty, whole)
    sources = (everything, nothing) if on_positive else (nothing, everything)
    return CutResult(halves[0], halves[1], sources, np.empty((0, 2), np.int64), np.empty(0),
                     np.empty((0, 3)), (len(halves[0].vertices), len(halves[1].vertices)), plane, on_plane,
                     0.0)


def cut(rig: Rig, normal, point, pose=None, cap: bool = False):
    """Cut ``rig`` with the plane through ``point`` with normal ``normal``.

    Parameters
    ----------
    rig : Rig
        The model to cut (never modified).
    normal : (3,) float
        The plane's normal, any non-zero length; it picks which half comes first.
    point : (3,) float
        A point of the plane.
    pose : Pose, optional
        Cut the mesh as posed (skinned) in this pose; the new vertices are placed in rest space so that
        skinning the halves in ``pose`` puts them exactly on the plane. None cuts the stored
        bind-pose vertices ``rig.vertices``. What a viewer shows at rest is ``skin(rig)``; where that
        differs from the stored mesh (bind matrices that are not the rest pose's, e.g. a mesh node
        with an offset), pass ``pose=rig.rest_pose()`` to cut what it shows.
    cap : bool, optional
        Close each half with planar caps over the loops the cut opened.

    Returns
    -------
    (positive, negative) : (Rig, Rig)
        positive: the part on the side the normal points to (signed distance > 0), negative: the other
        one; vertices on the plane are in both. Full skeleton and clips in both. When the plane misses
        the mesh: the whole rig (a copy) on the side it lies on and an empty rig on the other, with a
        ``PlaneMissesMeshWarning``.

    Raises
    ------
    InvalidInputError
        Zero or non-finite normal or point, wrong shapes, a rig without faces or with inconsistent
        arrays, a pose of another skeleton.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> hand, shoulder = cgaskin.cut(arm, [1, 0, 0], [1.55, 0, 0], cap=True)     # at the elbow
    >>> hand.n_vertices, shoulder.n_vertices, [clip.name for clip in hand.clips]
    (401, 417, ['wave'])
    >>> posed = cgaskin.cut(arm, [1, 0, 0], [1.55, 0, 0], pose=arm.pose("wave", 0.5))
    """
    result = _cut(rig, normal, point, pose, cap, with_sources=False)
    return result.positive, result.negative


# ---- caps ---------------------------------------------------------------------------------------------

