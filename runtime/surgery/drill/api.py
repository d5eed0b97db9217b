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

A bit that touches no face raises ``MissesMeshError``.
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
from ..surface import box_diagonal, mesh_arrays
from ..topology import rig_topology
from .assemble import assemble
from .bit import Bit, bit as checked_bit
from .inside import winding_number
from .patch import Patch
from .refine import refine
from .result import NEW_VERTEX, DrillResult
from .rim import open_hole
from .wall import build_walls

__all__ = ["drill", "drill_details", "DrillResult", "RIM_STEP", "NEW_VERTEX"]

#: the longest edge near a rim, as a fraction of the radius: 2 sin(pi / 25), about 25 edges around a hole
RIM_STEP = 2.0 * np.sin(np.pi / 25)


def drill_details(rig: Rig, start, end, radius, pose=None, wall: bool = True) -> DrillResult:
    """``drill`` with its bookkeeping (``DrillResult``); same arguments as ``drill``."""
    vertices, faces, joints, weights = mesh_arrays(rig)
    the_bit, wall = checked_bit(start, end, radius), checked_wall(wall)
    affines = None if pose is None else check_pose(rig, pose).bone_affines()
    positions = vertices if affines is None else skin_affine(vertices, joints, weights, affines)
    diagonal = rig_cached(rig, "drill.diagonal", lambda _: box_diagonal(vertices)) if affines is None else \
        box_diagonal(positions)
    return warned(drill_region(rig, the_bit, wall, affines, positions, diagonal,
                               lambda p: winding_number(positions, faces, p) > 0.5))


def warned(result: DrillResult) -> DrillResult:
    """``result``, with an ``OpenRimWarning`` where rims ran into an open boundary of the mesh."""
    if result.open_rims:
        warn(f"{result.open_rims} rim(s) of the hole run into an open boundary of the mesh: no wall joins them, "
             f"and the hole stays open there (a wall needs a rim that closes around the bit)", OpenRimWarning)
    return result


def checked_wall(wall) -> bool:
    """``wall`` as a bool; InvalidInputError for anything but True or False."""
    if not isinstance(wall, (bool, np.bool_)):
        raise InvalidInputError(f"wall must be True or False, got {wall!r}")
    return bool(wall)


def drill_region(rig: Rig, the_bit: Bit, wall: bool, affines, positions, diagonal: float, inside) -> DrillResult:
    """The drill of ``rig`` (checked arguments): ``positions`` (n, 3) its vertices in the space drilled
    (rest, or skinned by ``affines``), ``diagonal`` the size of the whole model there (the tolerances'
    scale), ``inside(point (3,)) -> bool`` whether a point is inside the whole model. ``rig`` may be a
    region of a larger mesh (an editing session's): the drill reads and changes only the faces it
    changes (``DrillResult.replaced``: of the faces it takes, those it splits or cuts), and their
    neighbours across the edges it splits."""
    with collection_paused():                   # (the patch's Python containers: see _shared/memory.py)
        return _drill_region(rig, the_bit, wall, affines, positions, diagonal, inside)


def _drill_region(rig: Rig, the_bit: Bit, wall: bool, affines, positions, diagonal: float, inside) -> DrillResult:
    faces = mesh_arrays(rig).faces
    step = RIM_STEP * the_bit.radius
    patch = Patch(positions, faces, rig_topology(rig))
    first = faces_near_bit(positions, faces, the_bit)
    tolerance = tol.on_plane * max(diagonal, the_bit.radius)
    rim, opened = np.empty(0, np.int64), 0
    if len(first):
        refine(patch, first, the_bit, step)
        rim, opened = open_hole(patch, the_bit, tolerance)
    if opened == 0:
        raise missed(the_bit, rig.name)
    walls, open_rims = build_walls(patch, rim, the_bit, step, inside) if wall else (0, 0)
    return assemble(rig, patch, rim, opened, walls, open_rims, the_bit, tolerance, affines, diagonal)


def missed(the_bit: Bit, name: str) -> MissesMeshError:
    """The error of a bit that does not reach into the mesh of the rig named ``name``."""
    return MissesMeshError(f"the bit (radius {the_bit.radius:g} around {the_bit.start.tolist()} -> "
                           f"{the_bit.end.tolist()}) does not reach into the mesh of {name!r}")


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
    start, end : (3,) float, the bit's travel (in the space drilled: rest, or posed in ``pose``); the
        bit takes away what lies within ``radius`` of the segment (a round tip at ``end``)
    radius : float > 0
    pose : Pose or None
        Drill the mesh as skinned in this pose; the new vertices are placed in rest space so that the
        result skinned in ``pose`` has them where the bit made them.
    wall : bool
        Line the hole with a wall on the bit's surface where the bit passes inside the model (from
        entry to exit, or to a blind hole's round bottom; a rim that does not go around the bit, where
        it grazes the model's side, is filled along the bit), so that a closed model stays closed; with
        False the hole is open, its rims a boundary of the mesh. A rim that runs into an open boundary
        of the mesh gets no wall (``OpenRimWarning``).

    Returns
    -------
    Rig : the drilled rig (same skeleton and clips; new vertices after the input vertices it keeps).

    Raises
    ------
    InvalidInputError : a radius that is not positive and finite, start equal to end, non-finite or
        misshapen points, a pose of another skeleton, an invalid rig.
    MissesMeshError : the bit does not reach into the mesh.

    Warns
    -----
    OpenRimWarning : ``wall=True`` and a rim runs into an open boundary of the mesh (no wall there).
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
