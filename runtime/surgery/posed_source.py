"""A surface held at rest, torn in a pose: the source of a posed stroke, and the bone influences
(``posed_bounds.Influences``) an editing session keeps for it.

A functional tear (``tear/rig_source.py``) and an editing session (``session.py``) both keep their
surface in rest space with a BVH over the rest positions. A stroke in a pose does not skin the mesh
nor build a BVH of the posed surface: ``PosedSource`` hands the stroke a posed tree whose boxes and
positions ``posed_bounds._pose_region`` fills where the stroke's queries reach (the bone-carried bounds
of ``posed_bounds.py``). Its tolerances scale with ``diagonal``: the rest bounding box's diagonal times
the largest scale of the bones in use (``posed_bounds.posed_scale``), the same for a session and for
the functional chain, so that both make the same decisions.
"""
from __future__ import annotations

import numpy as np

from ..animation.skinning import check_pose
from ..errors import InvalidInputError
from ..tolerances import tol
from .posed_bounds import PosedScratch, bone_masks, posed_scale, refresh_masks

__all__ = ["PosedSource", "bone_affines_of", "SessionMasks", "padding"]


def bone_affines_of(rig, pose) -> np.ndarray:
    """(B, 12) bone maps of ``pose`` (checked to be ``rig``'s), finite."""
    affines = check_pose(rig, pose).bone_affines()
    if not np.isfinite(affines).all():
        raise InvalidInputError("the pose's bone transforms overflow float64 (a dilation or translation "
                                "too large): the skinned surface would not be finite")
    return affines


def padding(weights) -> float:
    """The relative padding of a posed box: the BVH's, plus how far the weight rows' sums are from 1
    (a blend of weights that sum to s lies in s times the convex hull, not in it)."""
    sums = np.asarray(weights).sum(axis=1)
    return tol.box_padding + (float(np.abs(sums - 1.0).max()) if len(sums) else 0.0)


class PosedSource:
    """``source`` (a stroke source whose positions are its rest vertices and whose BVH holds them) in
    the pose of bone maps ``affines`` (B, 12): ``tree`` the rest BVH's arrays (``n_nodes`` rows in use)
    with its ``posed_bounds.Influences`` ``masks`` (a tuple); ``used`` (u,) int64 the bones in use; ``scratch`` a ``PosedScratch``;
    ``pad`` from ``padding``. The rest of the source interface is ``source``'s."""

    def __init__(self, source, affines, tree, n_nodes, masks, used, scratch: PosedScratch, pad: float):
        self._source = source
        self.affines = affines
        self.diagonal = source.diagonal * posed_scale(affines, used)
        self.bvh_arrays, self.posing = scratch.view(tree, n_nodes, masks, source.vertices, source.joints,
                                                    source.weights, affines, pad)
        self.positions = self.bvh_arrays[7]

    def __getattr__(self, name):
        return getattr(self._source, name)

    def check_hits(self, faces) -> None:
        """Nothing to check: the posed tree is made from the source's own BVH."""


class SessionMasks:
    """The bone influences (``posed_bounds.Influences``) of an editing session's ``DynamicBVH``, made on
    the first posed stroke and kept exact across its edits from then on (``edited``)."""

    def __init__(self, bvh, n_bones: int):
        self._bvh, self.n_bones, self._masks, self._rebuilds = bvh, n_bones, None, bvh.rebuilds

    def masks(self, joints, weights) -> np.ndarray:
        """The ``posed_bounds.Influences`` (a tuple) of the tree's nodes now (``joints``, ``weights`` the
        session's rows)."""
        if self._masks is None or self._rebuilds != self._bvh.rebuilds:
            arrays, self._rebuilds = self._bvh.arrays, self._bvh.rebuilds
            n_nodes = self._bvh.n_nodes            # (the tree's arrays have room for twice its faces: not used)
            self._masks = bone_masks(arrays[2], arrays[3], arrays[4], arrays[5], arrays[6], arrays[8], joints, weights,
                                     n_nodes, self.n_bones, n_nodes + n_nodes // 8)
        return self._masks

    def removing(self, faces) -> np.ndarray:
        """The leaves that hold ``faces`` before an edit removes them (what ``edited`` needs of them)."""
        return self._bvh.leaves(faces) if self._masks is not None else faces

    def edited(self, leaves_before, first_node, inserted, moved, joints, weights) -> None:
        """After an edit of the tree: ``leaves_before`` from ``removing``, ``first_node`` the node count
        before the edit, ``inserted`` and ``moved`` (k,) its faces."""
        if self._masks is None or self._rebuilds != self._bvh.rebuilds:
            self._masks = None                        # (a rebuild renumbered the nodes: made again when needed)
            return
        arrays, n_nodes = self._bvh.arrays, self._bvh.n_nodes
        if len(self._masks[0]) < n_nodes:
            grown = []
            for old in self._masks:
                new = np.zeros((max(n_nodes, len(old) * 3 // 2), old.shape[1]), old.dtype)
                new[:len(old)] = old
                grown.append(new)
            self._masks = tuple(grown)
        dirty = np.unique(np.concatenate((leaves_before, self._bvh.leaves(inserted), self._bvh.leaves(moved),
                                          np.arange(first_node, n_nodes))))
        refresh_masks(self._masks, arrays[2], arrays[3], self._bvh.parents, arrays[4], arrays[5], arrays[6], arrays[8],
                      joints, weights, dirty, self.n_bones)
