"""A surface held at rest, torn in a pose: the source of a posed stroke, and the bone influences
(``bone_influences.Influences``) an editing session keeps for it.

A functional tear (``tear/rig_source.py``) and an editing session (``session.py``) both keep their
surface in rest space with a BVH over the rest positions. A stroke in a pose does not skin the mesh
nor build a BVH of the posed surface: ``PosedSource`` hands the stroke a posed tree whose boxes and
positions ``posed_bounds._pose_region`` fills where the stroke's queries reach (the bone-carried bounds
of ``posed_bounds.py``). Its tolerances scale with ``diagonal``: the rest bounding box's diagonal times
the largest scale of the bones in use (``bone_influences.posed_scale``), the same for a session and for
the functional chain, so that both make the same decisions.
"""
from __future__ import annotations

import numpy as np

from ..animation.skinning import check_pose
from ..errors import InvalidInputError
from .bone_influences import posed_scale, refresh_influences, tree_influences
from .posed_bounds import PosedScratch

__all__ = ["PosedSource", "bone_affines_of", "SessionInfluences"]


def bone_affines_of(rig, pose) -> np.ndarray:
    """(B, 12) bone maps of ``pose`` (checked to be ``rig``'s), finite."""
    affines = check_pose(rig, pose).bone_affines()
    if not np.isfinite(affines).all():
        raise InvalidInputError("the pose's bone transforms overflow float64 (a dilation or translation "
                                "too large): the skinned surface would not be finite")
    return affines


class PosedSource:
    """``source`` (a stroke source whose positions are its rest vertices and whose BVH holds them) in
    the pose of bone maps ``affines`` (B, 12): ``tree`` the rest BVH's arrays (``n_nodes`` rows in use)
    with its ``bone_influences.Influences`` ``influences`` (a tuple); ``used`` (u,) int64 the bones in
    use; ``scratch`` a ``PosedScratch``; ``pad`` from ``bone_influences.weight_summary``. The rest of
    the source interface is ``source``'s."""

    def __init__(self, source, affines, tree, n_nodes, influences, used, scratch: PosedScratch, pad: float):
        self._source = source
        self.affines = affines
        self.diagonal = source.diagonal * posed_scale(affines, used)
        self.bvh_arrays, self.posing = scratch.view(tree, n_nodes, influences, source.vertices, source.joints,
                                                    source.weights, affines, pad)
        self.positions = self.bvh_arrays[7]

    def __getattr__(self, name):
        return getattr(self._source, name)

    def check_hits(self, faces) -> None:
        """Nothing to check: the posed tree is made from the source's own BVH."""


class SessionInfluences:
    """The bone influences (``bone_influences.Influences``) of an editing session's ``DynamicBVH``, made on
    the first posed stroke and kept exact across its edits from then on (``edited``)."""

    def __init__(self, bvh, n_bones: int):
        self._bvh, self.n_bones, self._influences, self._rebuilds = bvh, n_bones, None, bvh.rebuilds

    def influences(self, joints, weights) -> tuple:
        """The ``bone_influences.Influences`` (a tuple) of the tree's nodes now (``joints``, ``weights`` the
        session's rows)."""
        if self._influences is None or self._rebuilds != self._bvh.rebuilds:
            arrays, self._rebuilds = self._bvh.arrays, self._bvh.rebuilds
            # (rows for the tree's room too, as the tree has them: written only once nodes use them)
            self._influences = tree_influences(arrays[2], arrays[3], arrays[4], arrays[5], arrays[6], arrays[8],
                                               joints, weights, self._bvh.n_nodes, self.n_bones, len(arrays[0]))
        return self._influences

    @property
    def kept(self) -> bool:
        """Whether the influences are made and followed (after the first posed stroke)."""
        return self._influences is not None and self._rebuilds == self._bvh.rebuilds

    def removing(self, faces) -> np.ndarray:
        """The leaves that hold ``faces`` before an edit removes them (what ``edited`` needs of them)."""
        return self._bvh.leaves(faces) if self._influences is not None else faces

    def edited(self, leaves_before, first_node, inserted, moved, joints, weights):
        """After an edit of the tree: ``leaves_before`` from ``removing``, ``first_node`` the node count
        before the edit, ``inserted`` and ``moved`` (k,) its faces. Returns the nodes (k,) whose faces
        changed (their ancestors' boxes too), or None when the influences are not kept (none made yet, or a
        rebuild renumbered the nodes: made again when needed)."""
        if self._influences is None or self._rebuilds != self._bvh.rebuilds:
            self._influences = None
            return None
        arrays, n_nodes = self._bvh.arrays, self._bvh.n_nodes
        if len(self._influences[0]) < len(arrays[0]):          # the tree's room grew (by doubling)
            grown = []
            for old in self._influences:
                new = np.zeros((len(arrays[0]), old.shape[1]), old.dtype)
                new[:first_node] = old[:first_node]
                grown.append(new)
            self._influences = tuple(grown)
        dirty = np.unique(np.concatenate((leaves_before, self._bvh.leaves(inserted), self._bvh.leaves(moved),
                                          np.arange(first_node, n_nodes))))
        refresh_influences(self._influences, arrays[2], arrays[3], self._bvh.parents, arrays[4], arrays[5], arrays[6],
                           arrays[8],
                      joints, weights, dirty, self.n_bones)
        return dirty
