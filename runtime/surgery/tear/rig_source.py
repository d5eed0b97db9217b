"""A rig as the source of a tear stroke (``splice.py``), and the torn rig made from a stroke's splice.

What a stroke needs of the whole rig is built once per rig (its arrays, tear labels, boundary flags,
the rest surface's BVH and its nodes' bone influences) and kept while the rig lives (``_shared.cache``);
a stroke in a pose poses only what it reaches (``posed_source.PosedSource``), so nothing is built per
pose. A torn rig gets its boundary flags and highest label from the stroke that made it, so that a
chain of functional tears never rebuilds the whole welded topology, and the tip of the slit it made
(``tip.py``), which a stroke on it continues from.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..._shared.cache import rig_cached, seed
from ..._shared.frozen import kernel_array
from ...animation.skinning import skin
from ...errors import InvalidInputError
from ..bvh import TriangleBVH
from ..bone_influences import posed_scale, tree_influences, weight_summary
from ..posed_bounds import PosedScratch, no_posing
from ..posed_source import PosedSource, bone_affines_of
from ..surface import TEAR_LABEL, _labels, box_diagonal, mesh_arrays
from ..topology import boundary_flags

NO_POSING = no_posing()


def _arrays(rig):
    """The rig's arrays as the kernels take them (float64/int64, C-contiguous; attributes as ((n, c)
    float64, their original trailing shape), without the tear label), converted once per rig."""
    attributes = {}
    for name, values in rig.attributes.items():
        if name != TEAR_LABEL:
            values = kernel_array(np.asarray(values, dtype=np.float64))   # (read-only: its buffer, one kernel type)
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


def _no_tip(rig) -> int:
    """A rig that no stroke of this process made has no slit whose tip is known (``tip.py``)."""
    return -1


class _Rest:
    """The surface of a rig as stored: positions, bounding-box diagonal, and its BVH (built on first
    use: an editing session keeps a BVH of its own) with its nodes' bone influences."""

    def __init__(self, rig):
        mesh = mesh_arrays(rig)
        self.positions, self._faces, self._bvh = mesh.vertices, mesh.faces, None
        self.diagonal = box_diagonal(self.positions)
        self._mesh, self._n_bones = mesh, rig.skeleton.n_bones

    @cached_property
    def _summary(self) -> tuple:
        return weight_summary(self._mesh.joints, self._mesh.weights, self._n_bones)

    used = property(lambda self: self._summary[0], doc="(u,) int64 the bones in use (``weight_summary``)")
    pad = property(lambda self: self._summary[1], doc="a posed box's relative padding (``weight_summary``)")

    @property
    def bvh(self) -> TriangleBVH:
        if self._bvh is None:       # (checked arrays, kept while the rig lives: the BVH need not copy them)
            self._bvh = TriangleBVH.of_checked(self.positions, self._faces)
        return self._bvh

    @cached_property
    def influences(self) -> tuple:
        """The ``bone_influences.Influences`` (a tuple) of the BVH's nodes."""
        tree, mesh = self.bvh._arrays, self._mesh
        return tree_influences(tree.left, tree.right, tree.start, tree.count, tree.order, tree.faces, mesh.joints,
                               mesh.weights, len(tree.lo), self._n_bones, len(tree.lo))


class RigSource:
    """``rig`` (in ``pose``) as a stroke source; ``bvh`` a user's TriangleBVH of its surface, or None.

    In a pose, the surface is the rest one posed where the stroke reaches (``PosedSource``) unless the
    user gave a BVH of the posed surface: then the whole mesh is skinned, as that BVH holds it."""

    def __init__(self, rig, pose, bvh):
        mesh_arrays(rig)                                 # checks the rig first
        self.vertices, self.faces, self.joints, self.weights, self.labels, self.attributes = \
            rig_cached(rig, "tear.arrays", _arrays)
        self.boundary = rig_cached(rig, "tear.boundary", _boundary_flags)
        self.top_label = rig_cached(rig, "tear.top_label", _top_label)
        self.tip = rig_cached(rig, "tear.tip", _no_tip)
        rest = rig_cached(rig, "tear.rest", _Rest)
        self.positions, self.diagonal, self.affines, self.posing = rest.positions, rest.diagonal, None, NO_POSING
        self._rest, self._user_bvh, self._posed = rest, bvh, None
        if pose is not None:
            self.affines = bone_affines_of(rig, pose)
            if bvh is None:
                self._posed = PosedSource(self, self.affines, tuple(rest.bvh._arrays), rest.bvh.n_nodes,
                                          rest.influences, rest.used, PosedScratch(), rest.pad)
                self.positions, self.diagonal, self.posing = (self._posed.positions, self._posed.diagonal,
                                                              self._posed.posing)
            else:
                self.positions = skin(rig, pose)
                self.diagonal = rest.diagonal * posed_scale(self.affines, rest.used)
        if bvh is not None and (not isinstance(bvh, TriangleBVH) or bvh.n_faces != len(self.faces)
                                or bvh._arrays.positions.shape != self.positions.shape):
            raise InvalidInputError(f"bvh must be a TriangleBVH over the rig's {len(self.positions)} vertices "
                                    f"and {len(self.faces)} faces")

    @property
    def bvh_arrays(self) -> tuple:
        if self._posed is not None:
            return self._posed.bvh_arrays
        return tuple(self._rest.bvh._arrays if self._user_bvh is None else self._user_bvh._arrays)

    def check_hits(self, faces) -> None:
        """A user's BVH must hold the surface being torn: checked on the faces a stroke hit (-1: none)."""
        if self._user_bvh is None:
            return
        if any(not np.array_equal(self._user_bvh.triangle(face), self.positions[self.faces[face]])
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
    torn = rig._with_checked_mesh(vertices, np.concatenate((faces[keep], splice.pieces)), joints, weights, attributes)
    boundary = np.concatenate((source.boundary, np.zeros(added, bool)))
    boundary[splice.boundary_rows] = splice.boundary_flags
    seed(torn, "tear.boundary", boundary)
    seed(torn, "tear.top_label", max(source.top_label, int(splice.labels.max(initial=0))))
    seed(torn, "tear.tip", slit_tip(splice.stroke))
    return torn


def slit_tip(stroke: dict) -> int:
    """The tip of the slit a stroke made (its fields: ``StrokeResult``'s): the vertex of S_(i+1), which
    stays single where the stroke ended inside the surface; -1 where it ended on an existing boundary
    (it split there: the slit runs into an opening, no tip to continue from)."""
    return -1 if stroke["split"][-1] else int(stroke["side_a"][-1])
