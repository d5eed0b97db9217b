"""Drill a hole through a skinned mesh.

``drill(rig, start, end, radius, pose=None, wall=True) -> Rig``

The bit (``bit.py``) is the solid within ``radius`` of the segment start -> end, its travel. Steps:

1. Positions to drill: the stored vertices (``pose=None``), or the skinned positions in ``pose``.
2. The faces whose box meets the bit's box widened by the rim step form the patch; faces near the bit's
   surface are bisected until their edges are at most ``RIM_STEP`` of the radius (``refine.py``), so
   that the rim has about 25 edges around a hole however large the model's faces are.
3. The patch's faces inside the bit are taken away, faces crossing its surface keep their outside part,
   with new vertices exactly on the surface (``rim.py``).
4. New vertices (the refinement's and the rim's) get weights and attributes from the input vertices
   they lie between (``new_vertices.py``); a posed drill places them in rest space so that skinning the
   result in ``pose`` puts them where they were made (as a posed cut does).
5. The result keeps the input vertices it uses in their order (attributes and weights bit for bit),
   then the new vertices; the faces it did not split, cut or take away keep their order, then come the
   faces it made (``assemble.py``, with the ``DrillResult`` of ``result.py``).

6. ``wall=True``: where the bit passes inside the model, the hole gets a wall on the bit's surface
   (``wall.py``), so that a closed model stays closed; ``wall=False`` leaves the rims as boundaries.
   The wall has the rim's resolution around the axis (``RIM_STEP`` of the radius) and the mesh's along
   it (``axial_step``: the faces' edges around the bit), so a thin hole through a thick model makes
   as many rings as the mesh has there, not thickness / radius of them.

Limits, checked before any work: a radius below ``smallest_radius`` (``SMALLEST_RADIUS_ROUNDINGS``
roundings of float32 coordinates at the model's size) raises ``InvalidInputError`` naming it; a drill
whose ``predicted_new_vertices`` (an upper bound, from the bit and the faces around it) exceeds
``MAX_NEW_VERTICES`` raises ``InvalidInputError`` with the prediction and the cap. A bit that touches no
face raises ``MissesMeshError``; one that takes every face away, ``InvalidInputError``.
"""
from __future__ import annotations

import numpy as np

from ..._shared.cache import rig_cached
from ..._shared.jit import F1, F2, I2, kernel
from ..._shared.memory import collection_paused
from ..._shared.warn import warn
from ...animation.rig import Rig
from ...animation.skinning import check_pose, skin_affine
from ...errors import InvalidInputError, MissesMeshError, OpenRimWarning
from ...tolerances import tol
from ..surface import mesh_arrays
from ..topology import rig_topology
from .assemble import assemble
from .bit import Bit, bit as checked_bit
from .budget import axial_step, near_summary, new_vertex_bound
from .inside import winding_number
from .patch import Patch
from .refine import refine
from .result import NEW_VERTEX, DrillResult
from .rim import open_hole
from .wall import build_walls

__all__ = ["drill", "drill_details", "DrillResult", "RIM_STEP", "NEW_VERTEX", "MAX_NEW_VERTICES",
           "SMALLEST_RADIUS_ROUNDINGS", "predicted_new_vertices", "smallest_radius"]

#: the longest edge near a rim, as a fraction of the radius: 2 sin(pi / 25), about 25 edges around a hole
RIM_STEP = 2.0 * np.sin(np.pi / 25)
#: the most new vertices one hole may make: a drill whose ``predicted_new_vertices`` exceeds it raises
#: InvalidInputError before it runs (a million new vertices: about a second and 1 GB of work)
MAX_NEW_VERTICES = 1_000_000
#: the smallest radius, in roundings of the model's coordinates: float32's (as a model file holds them)
#: at the model's size D (its box diagonal, the drill's tolerances' scale), 64 eps32 D ~ 7.6e-6 D (a rim
#: step of 16 such roundings; Fox's 1.3e-3, the capsule arm's 2.7e-5)
SMALLEST_RADIUS_ROUNDINGS = 64
#: the rounding of float32 coordinates, relative (its machine epsilon)
FLOAT32_ROUNDING = float(np.finfo(np.float32).eps)


def drill_details(rig: Rig, start, end, radius, pose=None, wall: bool = True) -> DrillResult:
    """``drill`` with its bookkeeping: which input vertex each output vertex comes from, the new
    vertices, the faces replaced and made, the walls, the bit and the tolerance.

    Parameters
    ----------
    rig : Rig
        The model to drill.
    start, end : (3,) float
        The bit's travel, as ``drill``'s.
    radius : float
        The bit's radius, positive (at least ``smallest_radius(rig)``).
    pose : Pose, optional
        Drill the mesh as skinned in this pose (as ``drill``).
    wall : bool, optional
        Line the hole with a wall where the bit passes inside the model (as ``drill``).

    Returns
    -------
    DrillResult
        The drilled rig and the bookkeeping.

    Raises
    ------
    InvalidInputError
        As ``drill``.
    MissesMeshError
        The bit does not reach into the mesh.

    Warns
    -----
    OpenRimWarning
        As ``drill``.

    Examples
    --------
    >>> result = cgaskin.drill_details(cgaskin.capsule_arm(), [1, 0, -1], [1, 0, 1], 0.1)
    >>> result.rig.n_faces, result.wall_faces, len(result.rim)
    (2204, 332, 176)
    >>> int((result.made_in == -1).sum())                  # the walls' faces lie in no input face
    332
    """
    the_bit, wall = checked_bit(start, end, radius), checked_wall(wall)
    affines, positions, box, diagonal = drilled_space(rig, pose)
    faces = mesh_arrays(rig).faces

    def winding(point) -> float:               # (0 outside the model's box: no pass over the faces)
        return 0.0 if outside(box, point) else winding_number(positions, faces, point)
    result = drill_region(rig, the_bit, wall, affines, positions, diagonal, winding)
    if result.rig.n_faces == 0:
        raise takes_everything(the_bit, rig.name)
    return warned(result)


def drilled_space(rig: Rig, pose) -> tuple:
    """(the pose's bone maps or None, the positions drilled (n, 3): the vertices, or skinned in ``pose``,
    their bounding box (2, 3), its diagonal)."""
    vertices, _, joints, weights = mesh_arrays(rig)
    if pose is None:
        return (None, vertices) + rig_cached(rig, "drill.box", lambda _: sized_box(vertices))
    affines = check_pose(rig, pose).bone_affines()
    positions = skin_affine(vertices, joints, weights, affines)
    return (affines, positions) + sized_box(positions)


def sized_box(points) -> tuple:
    """(the least and greatest coordinates (2, 3) of ``points`` (n, 3), the box's diagonal), column by
    column (numpy reduces an (n, 3) array over its first axis ~20x slower than its three columns)."""
    if not len(points):
        return np.zeros((2, 3)), 0.0
    box = np.array([[points[:, k].min() for k in range(3)], [points[:, k].max() for k in range(3)]])
    return box, float(np.linalg.norm(box[1] - box[0]))


def outside(box, point) -> bool:
    """Whether ``point`` (3,) lies outside the (2, 3) box (where a model's winding number is 0, or below
    one half for an open surface: a plane separates the point from the surface)."""
    (x, y, z), (lo, hi) = point.tolist(), box.tolist()
    return x < lo[0] or y < lo[1] or z < lo[2] or x > hi[0] or y > hi[1] or z > hi[2]


def warned(result: DrillResult) -> DrillResult:
    """``result``, with an ``OpenRimWarning`` where rims ran into an open boundary of the mesh, or the
    walls left edges without exactly two faces (one warning for both)."""
    said = []
    if result.open_rims:
        said.append(f"{result.open_rims} rim(s) of the hole run into an open boundary of the mesh: no wall joins "
                    f"them, and the hole stays open there (a wall needs a rim that closes around the bit)")
    if result.unclosed_edges:
        said.append(f"{result.unclosed_edges} edge(s) on the bit's surface are left without exactly two faces: "
                    f"the walls do not close the hole there (an open surface around the bit, or one wound "
                    f"against its neighbours)")
    if said:
        warn("; ".join(said), OpenRimWarning)
    return result


def smallest_radius(rig: Rig, pose=None) -> float:
    """The smallest radius a drill of ``rig`` (in ``pose``) takes: ``SMALLEST_RADIUS_ROUNDINGS`` roundings
    of float32 coordinates at the model's size (its box diagonal where it is drilled)."""
    return smallest_at(drilled_space(rig, pose)[3])


def smallest_at(diagonal: float) -> float:
    """``smallest_radius`` of a model of size ``diagonal``."""
    return SMALLEST_RADIUS_ROUNDINGS * FLOAT32_ROUNDING * diagonal


def check_radius(the_bit: Bit, diagonal: float) -> None:
    """InvalidInputError for a radius below the smallest a model of size ``diagonal`` takes."""
    smallest = smallest_at(diagonal)
    if the_bit.radius < smallest:
        raise InvalidInputError(
            f"radius {the_bit.radius:.3g} is below the smallest this drill takes on this model, {smallest:.3g} "
            f"({SMALLEST_RADIUS_ROUNDINGS} roundings of float32 coordinates at its size {diagonal:.3g}): a rim that "
            f"fine would not survive the model's own rounding; give a radius of at least {smallest:.3g}")


def predicted_new_vertices(rig: Rig, start, end, radius, pose=None, wall: bool = True) -> int:
    """An upper bound on the new vertices ``drill(rig, start, end, radius, pose, wall)`` makes, found
    without drilling (the faces near the bit and their sizes: about the cost of a box query), as the
    drill finds it before it runs (it raises when this exceeds ``MAX_NEW_VERTICES``). The same checks of
    the arguments as ``drill`` (InvalidInputError, a radius below ``smallest_radius`` too); 0 for a bit
    that misses the mesh."""
    the_bit, wall = checked_bit(start, end, radius), checked_wall(wall)
    _, positions, _, diagonal = drilled_space(rig, pose)
    check_radius(the_bit, diagonal)
    faces = mesh_arrays(rig).faces
    return near_budget(positions, faces, faces_near_bit(positions, faces, the_bit), the_bit, wall)[0]


def near_budget(positions, faces, near, the_bit: Bit, wall: bool) -> tuple:
    """(``predicted_new_vertices``, the wall's ``axial_step``) from the faces ``near`` (k,) the bit
    (``faces_near_bit``, or any set that holds them) of ``faces`` over ``positions``."""
    step = RIM_STEP * the_bit.radius
    summary = near_summary(positions, faces, near, the_bit.start, the_bit.end, the_bit.radius, step, wall)
    axial = axial_step(summary, step)
    return new_vertex_bound(summary, the_bit, step, axial, wall), axial


def check_budget(predicted: int, the_bit: Bit) -> None:
    """InvalidInputError for a drill predicted to make more than ``MAX_NEW_VERTICES``."""
    if predicted > MAX_NEW_VERTICES:
        raise InvalidInputError(
            f"the drill (radius {the_bit.radius:.3g}) may make up to {predicted} new vertices, more than the cap of "
            f"{MAX_NEW_VERTICES} a hole may make (MAX_NEW_VERTICES): give a larger radius or a shorter travel")


def checked_wall(wall) -> bool:
    """``wall`` as a bool; InvalidInputError for anything but True or False."""
    if not isinstance(wall, (bool, np.bool_)):
        raise InvalidInputError(f"wall must be True or False, got {wall!r}")
    return bool(wall)


def drill_region(rig: Rig, the_bit: Bit, wall: bool, affines, positions, diagonal: float, winding,
                 budget=None) -> DrillResult:
    """The drill of ``rig`` (checked arguments): ``positions`` (n, 3) its vertices in the space drilled
    (rest, or skinned by ``affines``), ``diagonal`` the size of the whole model there (the tolerances'
    scale, and the smallest radius's), ``winding(point (3,)) -> float`` the whole model's winding number
    at a point. ``rig`` may be a region of a larger mesh (an editing session's): the drill reads and
    changes only the faces it changes (``DrillResult.replaced``: of the faces it takes, those it splits
    or cuts), and their neighbours across the edges it splits. The radius and the predicted size are
    checked first (``check_radius``, ``check_budget``); ``budget``, when given, is ``near_budget`` of
    the whole mesh (a session's, found once for the regions it tries)."""
    check_radius(the_bit, diagonal)
    with collection_paused():                   # (the patch's Python containers: see _shared/memory.py)
        return _drill_region(rig, the_bit, wall, affines, positions, diagonal, winding, budget)


def _drill_region(rig: Rig, the_bit: Bit, wall: bool, affines, positions, diagonal: float, winding,
                  budget) -> DrillResult:
    faces = mesh_arrays(rig).faces
    step = RIM_STEP * the_bit.radius
    first = faces_near_bit(positions, faces, the_bit)
    predicted, axial = near_budget(positions, faces, first, the_bit, wall) if budget is None else budget
    check_budget(predicted, the_bit)
    patch = Patch(positions, faces, rig_topology(rig))
    tolerance = tol.on_plane * max(diagonal, the_bit.radius)
    rim, opened = np.empty(0, np.int64), 0
    if len(first):
        refine(patch, first, the_bit, step)
        rim, opened = open_hole(patch, the_bit, tolerance)
    if opened == 0:
        raise missed(the_bit, rig.name)
    walls, open_rims, unclosed = build_walls(patch, rim, the_bit, step, axial, winding) if wall else (0, 0, 0)
    return assemble(rig, patch, rim, opened, walls, open_rims, unclosed, the_bit, tolerance, affines, diagonal)


def missed(the_bit: Bit, name: str) -> MissesMeshError:
    """The error of a bit that does not reach into the mesh of the rig named ``name``."""
    return MissesMeshError(f"the bit (radius {the_bit.radius:g} around {the_bit.start.tolist()} -> "
                           f"{the_bit.end.tolist()}) does not reach into the mesh of {name!r}")


def takes_everything(the_bit: Bit, name: str) -> InvalidInputError:
    """The error of a bit that would take away every face of the mesh of the rig named ``name``."""
    return InvalidInputError(f"the bit (radius {the_bit.radius:g} around {the_bit.start.tolist()} -> "
                             f"{the_bit.end.tolist()}) takes away the whole mesh of {name!r}: nothing would be left "
                             f"(give a smaller radius, or a travel that leaves part of the model)")


def bit_reach(the_bit: Bit) -> tuple:
    """(lo, hi) (3,): the box that holds every face a drill takes first (the bit's box widened by the
    rim step and the radius)."""
    reach = the_bit.radius + RIM_STEP * the_bit.radius
    return np.minimum(the_bit.start, the_bit.end) - reach, np.maximum(the_bit.start, the_bit.end) + reach


def faces_near_bit(positions, faces, the_bit: Bit) -> np.ndarray:
    """The faces (k,) whose box meets ``bit_reach``: the faces the drill takes first."""
    return _faces_near(positions, faces, *bit_reach(the_bit))


def drill(rig: Rig, start, end, radius, pose=None, wall: bool = True) -> Rig:
    """Drill a hole with a bit of ``radius`` travelling from ``start`` to ``end``.

    Parameters
    ----------
    rig : Rig
        The model to drill.
    start, end : (3,) float
        The bit's travel (in the space drilled: rest, or posed in ``pose``); the bit takes away what
        lies within ``radius`` of the segment (a round tip at ``end``).
    radius : float
        The bit's radius, positive and finite, at least ``smallest_radius(rig)``.
    pose : Pose, optional
        Drill the mesh as skinned in this pose; the new vertices are placed in rest space so that the
        result skinned in ``pose`` has them where the bit made them.
    wall : bool, optional
        Line the hole with a wall on the bit's surface where the bit passes inside the model (from
        entry to exit, or to a blind hole's round bottom; a rim that does not go around the bit, where
        it grazes the model's side, is filled along the bit), so that a closed model stays closed; with
        False the hole is open, its rims a boundary of the mesh. A rim that runs into an open boundary
        of the mesh gets no wall (``OpenRimWarning``).

    Returns
    -------
    Rig
        The drilled rig (same skeleton and clips; new vertices after the input vertices it keeps).

    Raises
    ------
    InvalidInputError
        A radius that is not positive and finite, or below ``smallest_radius(rig)``
        (``SMALLEST_RADIUS_ROUNDINGS`` = 64 float32 roundings of the model's diagonal, about 7.6e-6 of
        it; named in the message); start equal to end, non-finite or misshapen points, a pose of another
        skeleton, an invalid rig; a drill that ``predicted_new_vertices`` (an upper bound) says may make
        more than ``MAX_NEW_VERTICES`` (1,000,000) new vertices, before any work; a bit that takes away
        the whole mesh.
    MissesMeshError
        The bit does not reach into the mesh.

    Warns
    -----
    OpenRimWarning
        ``wall=True`` and a rim runs into an open boundary of the mesh (no wall there), or the walls
        leave edges without exactly two faces (shells that intersect each other: counted).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> holed = cgaskin.drill(arm, [1, 0, -1], [1, 0, 1], 0.1)   # through the arm, walled
    >>> arm.n_faces, holed.n_faces
    (1376, 2204)
    >>> open_hole = cgaskin.drill(arm, [1, 0, -1], [1, 0, 1], 0.1, wall=False)
    >>> len(cgaskin.rig_topology(open_hole).boundary_loops())  # its two rims
    2
    """
    return drill_details(rig, start, end, radius, pose, wall).rig


@kernel((F2, I2, F1, F1), cost=0.2)
def _faces_near(positions, faces, lo, hi):
    """The faces (k,) whose bounding box meets the box [lo, hi] (3,)."""
    out = np.empty(faces.shape[0], np.int64)
    count = 0
    for f in range(faces.shape[0]):
        meets = True
        for k in range(3):
            a, b, c = positions[faces[f, 0], k], positions[faces[f, 1], k], positions[faces[f, 2], k]
            if max(a, max(b, c)) < lo[k] or min(a, min(b, c)) > hi[k]:
                meets = False
                break
        if meets:
            out[count] = f
            count += 1
    return out[:count].copy()
