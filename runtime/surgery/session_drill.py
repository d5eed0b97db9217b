"""A session's drill on the region of its mesh around the bit, spliced back into the session's rows.

The drill (``drill/api.py``) changes only the faces it takes into its patch and splits edges only of
faces it takes: so it is run on a region, a rig of the session's faces whose (posed) boxes meet the
bit's reach widened by a margin, and it is exact there when it replaced no *border* face of the region
(a face with a corner where a face outside the region has one: across it, the drill could have wanted
to split an edge whose other faces it cannot see). The first margin is the largest face in the bit's
reach (about a ring of faces); while the drill replaces a border face, the margin doubles and the region is
drilled again, and after ``MAX_TRIES`` the region is the whole mesh, which has no border. In a region
the drill is the functional drill of the session's mesh (``cgaskin.drill_details(session.rig, ...)``),
which sees the same faces in the same order: its faces and new vertices are the same; the session keeps
the vertices inside the bit as rows that no face uses.

The region's result is then a splice, as a tear stroke's (``tear/splice.py``): the region's replaced
faces go, the faces made in their place and the new vertices are appended, and undo takes them back.
A hole costs the faces near the bit (the BVH's box query, in a pose through the bone-carried bounds of
``posed_bounds.py``), plus, for a blind hole or a bit that starts inside the mesh's box only, the
winding number of the whole mesh at a point (``wall.py``). A bit that would take every live face away is
refused, as the functional drill refuses it; so is one over the drill's cap on new vertices, before
the work (``predicted_session_drill`` gives the same prediction for a session without drilling).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._shared.frozen import kernel_array
from .._shared.ids import ascending, distinct
from ..animation.rig import Rig
from ..animation.skinning import skin_affine
from .drill.api import (DrillResult, bit_reach, check_budget, check_radius, checked_wall, drill_region, missed,
                        near_budget, outside, takes_everything)
from .drill.bit import bit as checked_bit
from .drill.inside import winding_number
from .dynamic_bvh import dyn_faces_near_plane
from .posed_bounds import pose_region
from .surface import TEAR_LABEL, MeshArrays, _labels, mesh_arrays
from .topology import boundary_flags
from .weld import _weld

#: how many times the margin doubles before the region is the whole mesh
MAX_TRIES = 5


class DrillSplice(NamedTuple):
    """A drill's changes as ``Surgery._apply`` takes a stroke's splice (no row of the session rewritten):
    new rows (vertices (v, 3), labels (v,), joints (v, 4), weights (v, 4), attributes {name: (v, c)}),
    ``removed`` (r,) the faces replaced, ``pieces`` (k, 3) the faces made (session rows), ``parents`` (k,)
    the replaced face each lies in, whose BVH leaf takes it (-1, a wall's: found from the root),
    ``boundary_rows`` (b,) with their ``boundary_flags`` (b,)."""

    rows: np.ndarray
    changed: np.ndarray
    vertices: np.ndarray
    labels: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    attributes: dict
    boundary_rows: np.ndarray
    boundary_flags: np.ndarray
    removed: np.ndarray
    kept: np.ndarray
    kept_corners: np.ndarray
    pieces: np.ndarray
    parents: np.ndarray


def session_drill(session, the_bit, wall: bool, posed) -> tuple:
    """(DrillResult of the region, DrillSplice) of a drill of ``session`` (checked arguments; ``posed``
    the session's ``PosedSource`` in the drill's pose, None at rest)."""
    faces, affines = session.faces, None if posed is None else posed.affines
    lo, hi = bit_reach(the_bit)
    diagonal = session.diagonal if posed is None else posed.diagonal
    reached = _faces_in(session, posed, lo, hi)
    check_radius(the_bit, diagonal)
    if len(reached) == 0:
        raise missed(the_bit, session._template.name)
    budget = near_budget(session.vertices if posed is None else posed.positions, faces, reached, the_bit, wall)
    check_budget(budget[0], the_bit)                # (before any region is made)
    winding = _winding(session, affines, _box(session, posed))
    margin = _largest_face(session, posed, reached)
    for attempt in range(MAX_TRIES + 1):
        whole = attempt == MAX_TRIES
        region = np.flatnonzero(session._alive.view) if whole else _faces_in(session, posed, lo - margin, hi + margin)
        rows = distinct(faces[region])
        rig = _region_rig(session, region, rows)
        mesh = mesh_arrays(rig)        # (the kernels' arrays: writable buffers, as the functional drill's)
        positions = mesh.vertices if affines is None else skin_affine(mesh.vertices, mesh.joints, mesh.weights, affines)
        result = drill_region(rig, the_bit, wall, affines, positions, diagonal, winding, budget)
        if whole or not _at_border(session, region, rows[distinct(mesh.faces[result.replaced])]):
            if result.rig.n_faces == 0 and len(region) == session._alive.view.sum():
                raise takes_everything(the_bit, session._template.name)
            return result, _splice(session, result, region, rows)
        margin *= 2.0


def predicted_session_drill(session, start, end, radius, pose=None, wall: bool = True) -> int:
    """``drill.api.predicted_new_vertices`` of ``session.drill(start, end, radius, pose, wall)``: the same
    bound, from the faces the session's BVH finds near the bit (no drill, no copy of the mesh); the same
    checks of the arguments (a radius below the smallest raises InvalidInputError)."""
    the_bit, wall = checked_bit(start, end, radius), checked_wall(wall)
    posed = None if pose is None and session.pose is None else session._posed(pose)
    check_radius(the_bit, session.diagonal if posed is None else posed.diagonal)
    near = _faces_in(session, posed, *bit_reach(the_bit))
    positions = session.vertices if posed is None else posed.positions
    return near_budget(positions, session.faces, near, the_bit, wall)[0]


def _largest_face(session, posed, faces) -> float:
    """The largest side of the (posed) boxes of ``faces`` (k,): a margin that holds a ring of faces."""
    positions = session.vertices if posed is None else posed.positions
    a, b, c = (positions[session.faces[faces, k]] for k in range(3))
    return float((np.maximum(np.maximum(a, b), c) - np.minimum(np.minimum(a, b), c)).max())


def _faces_in(session, posed, lo, hi) -> np.ndarray:
    """Sorted live faces whose (posed) box meets [lo, hi]."""
    if posed is None:
        return session._bvh.faces_in_box(lo, hi)
    none = np.zeros(3)
    pose_region(posed.bvh_arrays, posed.posing, np.zeros(4), lo, hi, 0.0)      # what the box reaches, posed
    return ascending(dyn_faces_near_plane(posed.bvh_arrays, lo, hi, none, 0.0, 0.0))


def _region_rig(session, region, rows) -> Rig:
    """The faces ``region`` (r,) with their vertices ``rows`` (v,) (ascending) as a rig, with the
    session's attributes and, once it has slits, its tear labels (as its ``rig`` has them)."""
    n = len(rows)
    attributes = {name: values[rows].reshape((n,) + tail) for name, (values, tail) in session.attributes.items()}
    if session._labelled:
        attributes[TEAR_LABEL] = session.labels[rows][:, None].astype(np.float64)
    template = session._template
    return Rig._of_checked(session.vertices[rows], np.searchsorted(rows, session.faces[region]),
                           session.joints[rows], session.weights[rows], template.skeleton, template.clips,
                           attributes, template.name)


def _at_border(session, region, corners) -> bool:
    """Whether a live face outside the faces ``region`` (r,) has a corner at the point (rest position) of
    one of the rows ``corners`` (k,) (a replaced face's)."""
    vertices, faces = session.vertices, session.faces
    points = vertices[corners]
    near = session._bvh.faces_in_box(points.min(axis=0), points.max(axis=0))
    outside = near[~np.isin(near, region, kind="table")]       # (a table over the ids' span: no sort)
    if not len(outside):
        return False
    welded, _ = _weld(np.concatenate((points, vertices[distinct(faces[outside])])), None)   # as the drill welds
    return bool(np.isin(welded[:len(points)], welded[len(points):], kind="table").any())


def _box(session, posed) -> np.ndarray:
    """(2, 3) a box that holds the session's live surface where it is drilled: its rest bounds, or the
    posed BVH's root box (bone-carried bounds: every face lies in it in the pose; ``_faces_in`` made it)."""
    if posed is None:
        return session._bounds
    return np.stack([posed.bvh_arrays[0][0], posed.bvh_arrays[1][0]])


def _winding(session, affines, box):
    """``winding(point)`` for the walls: the winding number of the session's whole live mesh (skinned by
    ``affines`` when posed), 0 outside ``box`` (2, 3); its arrays made on the first call that needs them
    (a blind hole's, or a bit's that starts inside the box)."""
    surface = []

    def winding(point) -> float:
        if outside(box, point):
            return 0.0
        if not surface:
            positions = session.vertices if affines is None else \
                skin_affine(session.vertices, session.joints, session.weights, affines)
            surface.extend((positions, session.faces[session._alive.view]))
        return winding_number(*surface, point)
    return winding


def _own_arrays(rig) -> MeshArrays:
    """The mesh arrays of a rig the drill made (as ``mesh_arrays`` gives them, not checked again: an
    empty one too, where the bit took away every face of the region)."""
    return MeshArrays(*(kernel_array(a) for a in (rig.vertices, rig.faces, rig.joints, rig.weights)))


def _splice(session, result: DrillResult, region, rows) -> DrillSplice:
    """The region's drill in the session's rows: the new vertices after its ``n`` rows, the pieces'
    corners as session rows."""
    out, n, first = _own_arrays(result.rig), session.n_vertices, result.first_new
    n_new = len(out.vertices) - first
    n_kept = len(region) - len(result.replaced)
    row_of = np.concatenate([rows[result.sources[:first]], n + np.arange(n_new)])
    pieces = row_of[out.faces[n_kept:]]
    labels = _labels(result.rig)
    flags = boundary_flags(out.vertices, out.faces, labels)
    touched = distinct(out.faces[n_kept:])
    attributes = {name: np.array(result.rig.attributes[name][first:], np.float64).reshape(n_new, rows_.shape[1])
                  for name, (rows_, _) in session.attributes.items()}
    none = np.empty(0, np.int64)
    return DrillSplice(rows=none, changed=none, vertices=out.vertices[first:], labels=labels[first:],
                       joints=out.joints[first:], weights=out.weights[first:], attributes=attributes,
                       boundary_rows=row_of[touched], boundary_flags=flags[touched], removed=region[result.replaced],
                       kept=none, kept_corners=np.empty((0, 3), np.int64), pieces=pieces,
                       parents=np.where(result.made_in >= 0, region[result.made_in], -1))
