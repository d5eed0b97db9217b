"""A rig as the source of a tear stroke (``splice.py``), and the torn rig made from a stroke's splice.

What a stroke needs of the whole rig is built once per rig (its arrays, tear labels, boundary flags)
and per rig and pose (the surface positions, their BVH and diagonal), and kept while the rig lives
(``_shared.cache``). A torn rig gets its boundary flags and highest label from the stroke that made
it, so that a chain of functional tears never rebuilds the whole welded topology.
"""
from __future__ import annotations

import weakref

import numpy as np

from ..._shared.cache import rig_cached, seed
from ...animation.skinning import check_pose, skin
from ...errors import InvalidInputError
from ..bvh import TriangleBVH
from ..surface import TEAR_LABEL, _labels, mesh_arrays
from ..topology import boundary_flags

#: posed surfaces kept per rig: a few poses per rig are plenty
POSED_SURFACES = 8


def _arrays(rig):
    """The rig's arrays as the kernels take them (float64/int64, C-contiguous; attributes as ((n, c)
    float64, their original trailing shape), without the tear label), converted once per rig."""
    attributes = {}
    for name, values in rig.attributes.items():
        if name != TEAR_LABEL:
            values = np.asarray(values, dtype=np.float64)
            attributes[name] = (np.ascontiguousarray(values.reshape(len(values), -1)), values.shape[1:])
    mesh = mesh_arrays(rig)
    return mesh.vertices, mesh.faces, mesh.joints, mesh.weights, _labels(rig), attributes


def _boundary_flags(rig) -> np.ndarray:
    """(n,) bool: the vertices on a boundary edge of the label-aware weld (``tear_topology``), found
    without building the whole topology (a stroke needs no more of it)."""
    mesh = mesh_arrays(rig)
    return boundary_flags(mesh.vertices, mesh.faces, _labels(rig))


def _top_label(rig) -> int:
    labels = rig_cached(rig, "tear.arrays", _arrays)[4]
    return max(0, int(labels.max())) if len(labels) else 0


class _Positions:
    """The surface of a rig in one pose: positions, bounding-box diagonal, bone maps, and its BVH
    (built on first use: an editing session keeps a BVH of its own)."""

    def __init__(self, positions, faces, affines):
        self.positions = np.ascontiguousarray(positions, dtype=np.float64)
        self.diagonal = float(np.linalg.norm(self.positions.max(axis=0) - self.positions.min(axis=0)))
        self.affines = affines
        self._faces, self._bvh = faces, None

    @property
    def bvh(self) -> TriangleBVH:
        if self._bvh is None:       # (checked arrays, kept while the rig lives: the BVH need not copy them)
            self._bvh = TriangleBVH.of_checked(self.positions, self._faces)
        return self._bvh


def _posed(rig, pose) -> _Positions:
    if pose is None:
        return rig_cached(rig, "tear.rest", lambda r: _Positions(mesh_arrays(r).vertices, mesh_arrays(r).faces, None))
    check_pose(rig, pose)
    posed = rig_cached(rig, "tear.posed", lambda _rig: weakref.WeakKeyDictionary())
    surface = posed.get(pose)
    if surface is None:
        surface = _Positions(skin(rig, pose), mesh_arrays(rig).faces, pose.bone_affines())
        if len(posed) >= POSED_SURFACES:
            posed.popitem()
        posed[pose] = surface
    return surface


class RigSource:
    """``rig`` (in ``pose``) as a stroke source; ``bvh`` a user's TriangleBVH of its surface, or None."""

    def __init__(self, rig, pose, bvh):
        mesh_arrays(rig)                                 # checks the rig first
        self.vertices, self.faces, self.joints, self.weights, self.labels, self.attributes = \
            rig_cached(rig, "tear.arrays", _arrays)
        self.boundary = rig_cached(rig, "tear.boundary", _boundary_flags)
        self.top_label = rig_cached(rig, "tear.top_label", _top_label)
        surface = _posed(rig, pose)
        self.positions, self.diagonal, self.affines = surface.positions, surface.diagonal, surface.affines
        if bvh is not None and (not isinstance(bvh, TriangleBVH) or bvh.n_faces != len(self.faces)
                                or bvh._arrays.positions.shape != self.positions.shape):
            raise InvalidInputError(f"bvh must be a TriangleBVH over the rig's {len(self.positions)} vertices "
                                    f"and {len(self.faces)} faces")
        self._surface, self._user_bvh, self._rig = surface, bvh, rig

    @property
    def _bvh(self) -> TriangleBVH:
        return self._surface.bvh if self._user_bvh is None else self._user_bvh

    @property
    def bvh_arrays(self) -> tuple:
        return tuple(self._bvh._arrays)

    def check_hits(self, faces) -> None:
        """A user's BVH must hold the surface being torn: checked on the faces a stroke hit (-1: none)."""
        if self._user_bvh is None:
            return
        if any(not np.array_equal(self._bvh.triangle(face), self.positions[self.faces[face]])
               for face in faces.tolist() if face >= 0):
            raise InvalidInputError("bvh was built from other positions than the surface being torn "
                                    "(the stored vertices, or the skinned positions in the given pose)")


def torn_rig(rig, source: RigSource, splice):
    """The rig ``splice`` makes of ``rig``: its vertex rows rewritten and extended, the replaced faces
    dropped, the pieces appended (the kept faces keep their order)."""
    n, rows = len(source.vertices), splice.rows
    added = len(splice.vertices) - len(rows)

    def merged(values, after, rewritten=False):
        out = np.empty((n + added,) + values.shape[1:], values.dtype)
        out[:n] = values
        out[n:] = after[len(rows):]
        if rewritten:                 # (a stroke rewrites only the labels and positions of its rows)
            out[rows[splice.changed]] = after[splice.changed]
        return out

    vertices, labels = merged(source.vertices, splice.vertices, True), merged(source.labels, splice.labels, True)
    joints, weights = merged(source.joints, splice.joints), merged(source.weights, splice.weights)
    attributes = {name: merged(values, splice.attributes[name]).reshape((n + added,) + tail)
                  for name, (values, tail) in source.attributes.items()}
    if splice.stroke["split"].any() or TEAR_LABEL in rig.attributes:
        attributes[TEAR_LABEL] = labels[:, None].astype(np.float64)
    faces = source.faces.copy()
    faces[splice.kept] = splice.kept_corners
    keep = np.ones(len(faces), bool)
    keep[splice.removed] = False
    torn = rig.with_mesh(vertices, np.concatenate((faces[keep], splice.pieces)), joints, weights, attributes)
    boundary = np.concatenate((source.boundary, np.zeros(added, bool)))
    boundary[splice.boundary_rows] = splice.boundary_flags
    seed(torn, "tear.boundary", boundary)
    seed(torn, "tear.top_label", max(source.top_label, int(splice.labels.max(initial=0))))
    return torn
