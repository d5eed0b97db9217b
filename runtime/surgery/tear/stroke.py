"""Tear a skinned mesh with a scalpel: a slit along the surface, between two positions of a blade.

``tear(rig, scalpel_from, scalpel_to, pose=None, opening=0.0) -> Rig``

The scalpel is a segment from its handle ``a`` to its tip ``b``; ``scalpel_from = (a0, b0)`` is the
blade at time t_i and ``scalpel_to = (a1, b1)`` at t_{i+1}. Steps (design.md section 4, "Tear"):

1. **Surface.** The stored vertices (``pose=None``), or the skinned positions in ``pose`` (a posed
   tear). A BVH over its triangles is built once per rig (and pose) and cached, and so are the
   vertices that lie on a boundary. The stroke then works on its *patch* (``patch.py``): the faces
   that come within the snap distance of the tear plane inside the region the blade swept, with
   their own welded topology (attribute-split copies of a vertex are one, so that the tear crosses
   UV/normal seams), so that it costs what it touches (``splice.py``; an editing session,
   ``cgaskin.Surgery``, runs the same stroke on its own mutable arrays).
2. **Where the blade meets the skin.** S_i is the *first* crossing of segment a0 -> b0 with the
   surface going from the handle a0 towards the tip b0 (the skin the blade enters); S_{i+1} likewise
   for a1 -> b1. The BVH query is two-sided and watertight (``surgery/bvh.py``). A hit within
   ``tol.snap`` of a mesh vertex is that vertex (this is what lets a stroke that starts where
   the previous one ended continue the same slit), and one within it of where the plane crosses an
   edge of the hit face is that crossing (no zero-area slivers when the blade meets an edge). A
   blade that passes within it of a boundary vertex before its first hit meets the surface there
   (the end of a slit opened wide is the tip of a wedge-shaped gap, which the blade that ended the
   stroke would otherwise slip through by rounding).
3. **Tear plane** through S_i, a1 and b1 (generated ``plane_from_points``): it holds the blade at
   t_{i+1} and both surface points, so the tear runs where the blade swept from S_i to its new
   position. When S_i lies on the line a1 b1 (the blade slid along itself) the plane falls back to
   S_i, S_{i+1} and the blade at t_i (a0 or b0), then to the plane through S_i S_{i+1} that holds the
   mean surface normal of the two hit faces; a stroke with S_i = S_{i+1} raises ``InvalidInputError``.
4. **Path.** The plane cuts the surface in a curve; the path follows it from S_i to S_{i+1} across
   faces (signed distances by the generated ``point_plane_distance``, crossing parameters by
   ``segment_plane``), in both directions at once, and keeps the shorter: a front-propagation over
   the curve in which the shortest way to a node wins (so the face count bounds it, with no other step
   cap) and follows the curve through vertices that lie on the plane and along edges that lie in it;
   a hit on an edge in the plane is a point of that edge, and across faces that lie in the plane the
   path goes straight from S_i towards S_{i+1} (``flat.py``). The
   path stays in the region the blade swept (``region.py``: the hull of the blade at both times,
   widened by the stroke's length and a face): it never detours round an obstacle. Where the curve
   meets an existing slit (or any opening of the surface), the path jumps across it to the curve
   on the other side, so that the new slit crosses the old one (an X junction) or ends on it (a T
   junction). A curve that does not reach S_{i+1} within the region, and a stroke that would only
   run through existing openings, raise ``TearPathError``.
5. **Re-triangulation.** Every crossed face is split so that the path is a chain of mesh edges: the
   edge crossings and the two end points become new vertices, with weights interpolated (edge: by
   the edge parameter t; inside a face: by its barycentric coordinates from the generated
   ``barycentric``), the 4 largest kept and renormalised, and NORMAL/TEXCOORD_0 (and any other
   attribute) interpolated likewise. Each attribute-split copy of a crossed seam edge gets its own new
   vertex (own UVs), all at one position computed from the welded edge.
6. **Opening the slit.** Each path vertex except the two ends is duplicated: faces on one side of the
   path keep the original copies, faces on the other side get new ones, so the surface is open along
   the path. The two ends stay single (the tear stops inside the surface there: a slit, not a
   hole) -- unless an end lies on an existing boundary (the end of an earlier slit, or a border of an
   open mesh): then it is split too, and the new slit continues the old one. A path of one segment
   (both ends in one face, or on one edge) gets its midpoint as a third vertex, which opens.
   ``opening`` > 0 moves the two sides apart by ``opening`` along the plane normal (the side the
   normal points to goes +): half each, less on a side where a face beside the path has too little
   room for it (``opening.py``), so that no face folds over.
7. **Posed tears** place every new vertex in rest space by inverting its blended 3x4 transform,
   so that skinning the torn rig in ``pose`` puts it exactly on the posed path (and the opening
   offset goes through the inverse blended linear part). The copies of one path point share one
   rest position (solved with the first copy's weights), so they stay welded.

Slit copies with opening 0 have the same positions as the copies they were split from, like
attribute-split seam copies. To tell them apart in later strokes, the torn rig carries the per-vertex
attribute ``TEAR_LABEL`` ("_TEAR", (n, 1) float): vertices are welded only when both their positions
and their labels are equal; each stroke gives the far side of its slit a new label. Rigs without it
behave as if it were 0 everywhere. (glTF export writes it as the application attribute "_TEAR".)

The caller's rig is never modified; vertices not on the path keep their index, position, weights and
attributes; faces not crossed keep their corners (the crossed ones are replaced by their pieces at the
end of the face array).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..._shared.checks import float_array, real_number
from ...animation.rig import Rig
from ...errors import InvalidInputError, MissesMeshError, PlacementWarning, TearPathError
from ...tolerances import tol
from ..bvh import TriangleBVH
from ..surface import TEAR_LABEL, tear_topology
from .records import FROM_MISSES, NO_MOTION, NO_PLANE, OK, TO_MISSES, Ends
from .rig_source import RigSource, torn_rig
from .splice import stroke_splice

__all__ = ["tear", "tear_stroke", "TearResult", "StrokeResult", "TearPathError", "TearPlacementWarning",
           "tear_topology", "TEAR_LABEL", "SNAP_TOLERANCE", "PLACEMENT_TOLERANCE"]

#: the tolerances a tear uses (``cgaskin.tolerances.tol``), under their former names
SNAP_TOLERANCE, PLACEMENT_TOLERANCE = tol.snap, tol.placement


#: a posed tear's new vertex could not be placed exactly on the posed path (its former name)
TearPlacementWarning = PlacementWarning


@dataclass(frozen=True, eq=False)
class StrokeResult:
    """A tear stroke's bookkeeping (an editing session's ``Surgery.tear`` returns it; ``tear_stroke``
    returns it with the torn rig, as ``TearResult``).

    Parameters
    ----------
    plane : (4,) float64
        The dual plane n̂ + d e∞ of the tear, in the surface's space (posed if posed).
    points : (k, 3) float64
        The path points in the surface's space, S_i first and S_{i+1} last.
    kinds : (k,) int64
        What each path point is: 0 an existing vertex, 1 an edge crossing, 2 a point inside a face
        (the ends, or the midpoint of a one-segment path).
    side_a, side_b : (k,) int64
        One vertex of each path point in the torn mesh on the side the plane normal points to, and
        one on the other side (equal where the point was not split: the slit's ends inside the
        surface); other attribute-split copies may exist.
    split : (k,) bool
        Whether the path point was split into two sides.
    hits : (2, 3) float64
        S_i and S_{i+1} as the scalpel met the surface (before snapping).
    jumps : (k,) bool
        Whether the path reaches the point by jumping from the previous one across an opening of the
        surface (where it crosses an existing slit: both points lie on its sides).

    Examples
    --------
    >>> blade_from = [[1.0, 0.05, 1.0], [1.0, 0.05, 0.0]]          # handle above the arm, tip below
    >>> blade_to = [[1.5, 0.05, 1.0], [1.5, 0.05, 0.0]]
    >>> stroke = cgaskin.tear_stroke(cgaskin.capsule_arm(), blade_from, blade_to)
    >>> stroke.points.shape, stroke.kinds.tolist()[:4], int(stroke.split.sum()), bool(stroke.jumps.any())
    ((13, 3), [1, 1, 1, 1], 11, False)
    >>> stroke.hits.round(3)                                       # where the blade met the skin
    array([[1.  , 0.05, 0.24],
           [1.5 , 0.05, 0.24]])
    """

    plane: np.ndarray
    points: np.ndarray
    kinds: np.ndarray
    side_a: np.ndarray
    side_b: np.ndarray
    split: np.ndarray
    hits: np.ndarray
    jumps: np.ndarray


@dataclass(frozen=True, eq=False)
class TearResult(StrokeResult):
    """A tear stroke with its bookkeeping (``tear_stroke``): a ``StrokeResult`` with the torn rig.

    Parameters
    ----------
    plane : (4,) float64
        The dual plane n̂ + d e∞ of the tear, in the surface's space (posed if posed).
    points : (k, 3) float64
        The path points in the surface's space, S_i first and S_{i+1} last.
    kinds : (k,) int64
        What each path point is: 0 an existing vertex, 1 an edge crossing, 2 a point inside a face.
    side_a, side_b : (k,) int64
        One vertex of each path point in ``rig`` on the side the plane normal points to, and one on
        the other side (equal where the point was not split).
    split : (k,) bool
        Whether the path point was split into two sides.
    hits : (2, 3) float64
        S_i and S_{i+1} as the scalpel met the surface (before snapping).
    jumps : (k,) bool
        Whether the path reaches the point by jumping across an opening of the surface.
    rig : Rig
        The torn rig.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> result = cgaskin.tear_stroke(arm, [[1.0, 0.05, 1.0], [1.0, 0.05, 0.0]],
    ...                              [[1.5, 0.05, 1.0], [1.5, 0.05, 0.0]])
    >>> arm.n_vertices, result.rig.n_vertices, len(result.points)
    (690, 714, 13)
    >>> result.side_a[:3].tolist(), result.side_b[:3].tolist()     # the first point (an end) is not split
    ([690, 691, 692], [690, 703, 704])
    """

    rig: Rig


def _scalpel(value, name):
    """(a, b) handle and tip, (3,) float64 each, from a (2, 3) pair."""
    # the shared check, as the cut's: it refuses strings and complex values (numpy would drop the
    # imaginary part with a mere ComplexWarning) and names a non-finite entry
    arr = float_array(value, name)
    if arr.shape != (2, 3):
        raise InvalidInputError(f"{name} must be a pair of points (handle a, tip b), shape (2, 3), "
                                f"got shape {arr.shape}")
    handle, tip = arr                           # (3,) views, C-contiguous
    if handle.tolist() == tip.tolist():         # (a list comparison costs a quarter of numpy's here)
        raise InvalidInputError(f"{name}: the handle and the tip coincide at {arr[0].tolist()}; the "
                                f"scalpel must be a segment of non-zero length")
    return handle, tip


def check_blade(value, name: str) -> np.ndarray:
    """(2, 3) float64 handle and tip of one blade position, checked (``name`` the argument's)."""
    return np.array(_scalpel(value, name))


def check_opening(value) -> float:
    opening = real_number(value, "opening")
    if opening < 0:
        raise InvalidInputError(f"opening must be a finite number >= 0, got {value!r}")
    return opening


def tear_stroke(rig: Rig, scalpel_from, scalpel_to, pose=None, opening: float = 0.0,
                bvh: TriangleBVH | None = None) -> TearResult:
    """One scalpel stroke, with its bookkeeping (``tear`` returns only the rig).

    Parameters
    ----------
    rig : Rig
        The model to tear (never modified).
    scalpel_from, scalpel_to : (2, 3) float
        The blade (handle a, tip b) at t_i and at t_{i+1}.
    pose : Pose, optional
        Tear the mesh as skinned in this pose (default: the stored bind-pose vertices
        ``rig.vertices``). What a viewer shows at rest is ``skin(rig)``; where that differs from
        the stored mesh (bind matrices that are not the rest pose's, e.g. a mesh node with an
        offset), pass ``pose=rig.rest_pose()`` to tear what it shows.
    opening : float >= 0
        Distance the two sides of the slit are moved apart, along the tear plane's normal (in the
        pose's space for a posed tear).
    bvh : TriangleBVH, optional
        A BVH of the surface being torn (``TriangleBVH(rig.vertices, rig.faces)``, or of the skinned
        positions in ``pose``); by default one is built on first use and cached per rig and pose.

    Returns
    -------
    TearResult
        The torn rig (``rig``) and the stroke's path, plane and hits.

    Raises
    ------
    MissesMeshError
        A scalpel segment does not meet the surface (the message names which).
    TearPathError
        The plane's section of the surface does not lead from S_i to S_{i+1} within the region the
        blade swept, or the stroke runs only through existing openings (nothing to tear).
    InvalidInputError
        Wrong shapes, non-finite values, a negative opening, a zero-length blade, a stroke that does
        not move across the surface, a pose of another skeleton, a BVH of other positions.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> result = cgaskin.tear_stroke(arm, [[1.0, 0.05, 1.0], [1.0, 0.05, 0.0]],
    ...                              [[1.5, 0.05, 1.0], [1.5, 0.05, 0.0]], opening=0.02)
    >>> result.rig.n_vertices, len(result.points), int(result.split.sum())
    (714, 13, 11)
    >>> float(abs(result.plane[1]))                                # the tear plane is y = 0.05
    1.0
    """
    if not isinstance(rig, Rig):
        raise InvalidInputError(f"rig must be a cgaskin.Rig, got {type(rig).__name__}")
    blades = check_blades(scalpel_from, scalpel_to)
    opening = check_opening(opening)
    source = RigSource(rig, pose, bvh)
    splice = stroke_splice(source, blades, opening, check_ends, check_path)
    return TearResult(rig=torn_rig(rig, source, splice), **splice.stroke)


def check_blades(scalpel_from, scalpel_to) -> np.ndarray:
    """(4, 3) float64 handle and tip at t_i, then at t_(i+1), checked."""
    blades = None
    try:                                 # (the usual case at once: both well formed)
        if type(scalpel_from) is np.ndarray and type(scalpel_to) is np.ndarray:    # (half np.array's cost)
            if scalpel_from.shape == scalpel_to.shape == (2, 3) and scalpel_from.dtype.kind in "fiu" \
                    and scalpel_to.dtype.kind in "fiu":
                blades = np.empty((4, 3))        # (C-contiguous, whatever the inputs' strides: the kernels')
                blades[:2], blades[2:] = scalpel_from, scalpel_to
        else:
            blades = np.array((scalpel_from, scalpel_to))     # (no dtype: a cast would take strings and
            if blades.shape == (2, 2, 3) and blades.dtype.kind in "fiu":     # drop imaginary parts)
                blades = blades.reshape(4, 3).astype(np.float64, copy=False)
            else:
                blades = None
    except (TypeError, ValueError):
        pass
    if blades is not None:
        x = blades.ravel().tolist()          # (Python floats: a tenth of numpy's calls on 12 numbers)
        if math.isfinite(sum(x)) and x[0:3] != x[3:6] and x[6:9] != x[9:12]:
            return blades
    # (the slow way, which names what is wrong)
    return np.array([*_scalpel(scalpel_from, "scalpel_from"), *_scalpel(scalpel_to, "scalpel_to")])


def check_ends(ends: Ends) -> None:
    """The errors of steps 2-3, named for the user (a scalpel that misses is found before: splice.py)."""
    if ends.status == OK:
        return
    if ends.status in (FROM_MISSES, TO_MISSES):
        name = "scalpel_from" if ends.status == FROM_MISSES else "scalpel_to"
        raise MissesMeshError(f"the scalpel {name} does not meet the surface")
    if ends.status == NO_MOTION:
        raise InvalidInputError(f"the stroke does not move across the surface: the scalpel meets it at "
                                f"the same point {ends.points[0].tolist()} at both times (nothing to tear)")
    if ends.status == NO_PLANE:
        raise InvalidInputError("cannot place a tear plane: the scalpel at both times and the surface "
                                "normal are all aligned with the stroke from S_i to S_{i+1}")


def check_path(ends: Ends, path) -> None:
    """The errors of step 4: no path, or nothing to tear."""
    if path is not None and len(path.nodes):
        return
    s_pos, t_pos = ends.points
    if path is None:
        raise TearPathError(
            f"the tear plane's section of the surface, followed from S_i = {s_pos.tolist()} within the "
            f"region the blade swept, does not reach S_(i+1) = {t_pos.tolist()}: the surface between "
            f"them leaves that region (a fold, or a boundary or slit of the mesh that the section "
            f"cannot cross there), or they lie on different pieces of the section (use shorter strokes)")
    raise TearPathError(
        f"nothing to tear: the stroke from S_i = {s_pos.tolist()} to S_(i+1) = {t_pos.tolist()} runs "
        f"only through openings the surface already has (an existing slit or hole)")


def tear(rig: Rig, scalpel_from, scalpel_to, pose=None, opening: float = 0.0,
         bvh: TriangleBVH | None = None) -> Rig:
    """Tear ``rig`` along the surface between two positions of a scalpel; returns the torn rig.

    See the module docstring for the algorithm and ``tear_stroke`` for a variant that also returns the
    path. Tearing the result again from where this stroke ended continues the slit.

    Parameters
    ----------
    rig : Rig
        The model to tear (never modified).
    scalpel_from, scalpel_to : (2, 3) float
        The blade (handle a, tip b) at t_i and at t_{i+1}.
    pose : Pose, optional
        Tear the mesh as skinned in this pose; None (default) tears the stored vertices
        ``rig.vertices``, ``rig.rest_pose()`` what a viewer shows at rest.
    opening : float >= 0, optional
        How far apart the two sides of the slit are moved, along the tear plane's normal.
    bvh : TriangleBVH, optional
        A BVH of the surface being torn; by default one is built and cached per rig and pose.

    Returns
    -------
    Rig
        The torn rig: the slit's vertices duplicated on its two sides, the crossed faces replaced by
        their pieces at the end of the face array; full skeleton and clips.

    Raises
    ------
    MissesMeshError, TearPathError, InvalidInputError
        As ``tear_stroke``.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> torn = cgaskin.tear(arm, [[1.0, 0.05, 1.0], [1.0, 0.05, 0.0]],
    ...                     [[1.5, 0.05, 1.0], [1.5, 0.05, 0.0]])
    >>> arm.n_vertices, torn.n_vertices, len(arm.faces), len(torn.faces)
    (690, 714, 1376, 1402)
    >>> longer = cgaskin.tear(torn, [[1.5, 0.05, 1.0], [1.5, 0.05, 0.0]],     # continues the slit
    ...                       [[1.8, 0.05, 1.0], [1.8, 0.05, 0.0]])
    """
    return tear_stroke(rig, scalpel_from, scalpel_to, pose=pose, opening=opening, bvh=bvh).rig
