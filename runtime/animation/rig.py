"""The rig data model: a skinned triangle mesh, its skeleton, and its animation clips.

Conventions (glTF 2.0 semantics, whatever the source format):

* ``Skeleton`` holds *nodes*: every skin joint plus all of its ancestors, in topological order
  (a parent's index is always smaller than its children's). Each node has a rest local transform
  relative to its parent, as TRS (translation, unit quaternion ``(x, y, z, w)``, per-axis scale) and
  as the exact 4x4 matrix (which differs from the TRS only for nodes given by a matrix with shear).
* ``Skeleton.bone_nodes`` and ``Skeleton.inverse_bind`` list the *bones* (the skin's joints): bone
  ``k`` deforms by ``G[bone_nodes[k]] @ inverse_bind[k]``, where ``G`` is the node's global transform
  in the pose. ``Rig.joints`` indexes bones.
* ``Rig.vertices`` are the bind-pose positions as stored in the file (attribute-split: vertices are
  duplicated along UV/normal seams exactly as the file has them).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InvalidInputError
from .clip import CHANNEL_PATHS, INTERPOLATIONS, Channel, Clip
from .pose import Pose
from .poses import Poses
from .skeleton import Skeleton

#: the whole data model in one import
__all__ = ["Rig", "Skeleton", "Clip", "Channel", "INTERPOLATIONS", "CHANNEL_PATHS"]


@dataclass(frozen=True, eq=False)
class Rig:
    """A skinned triangle mesh.

    vertices : (n, 3) float64 bind-pose positions
    faces : (m, 3) int64 vertex indices, counter-clockwise
    joints : (n, 4) int64 bone indices (unused slots hold 0 with weight 0)
    weights : (n, 4) float64, finite, >= 0, each row sums to 1
    skeleton : Skeleton
    clips : list[Clip]
    attributes : dict name -> (n, k) float64 per-vertex data carried through cut/tear/export
        (glTF names: "NORMAL", "TEXCOORD_0")
    name : str
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    skeleton: Skeleton
    clips: list = field(default_factory=list)
    attributes: dict = field(default_factory=dict)
    name: str = "rig"

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    def clip_index(self, clip) -> int:
        """Index of a clip given by name or index; a clear error lists the valid names."""
        names = [c.name for c in self.clips]
        if isinstance(clip, (int, np.integer)):
            if not 0 <= clip < len(self.clips):
                raise InvalidInputError(f"clip index {clip} out of range: the rig has {len(self.clips)} clips")
            return int(clip)
        if clip in names:
            return names.index(clip)
        raise InvalidInputError(f"unknown clip {clip!r}; valid clips: {', '.join(map(repr, names)) or 'none'}")

    def rest_pose(self):
        """The rest (node) pose of the skeleton, as a ``Pose``."""
        return Pose.rest(self.skeleton)

    def bind_pose(self):
        """The pose whose skinning returns ``vertices`` unchanged: every bone's global transform is
        the inverse of its inverse bind matrix (differs from the rest pose in some files)."""
        return Pose.bind(self.skeleton)

    def pose(self, clip=0, time: float = 0.0, rotation_blend: str = "slerp") -> Pose:
        """The pose of a clip (name or index) at ``time`` seconds, glTF sampler semantics, in one
        compiled call: rotations by slerp on the shorter arc (``"slerp"``, as glTF) or the normalised
        linear blend (``"linear"``); a time before the first key or after the last clamps to that key
        (no error). InvalidInputError for an unknown clip (the message lists the rig's clips) and a
        time that is not a finite real number."""
        return Pose.from_clip(self.skeleton, self.clips[self.clip_index(clip)], time, rotation_blend)

    def poses(self, clip=0, times=(0.0,), rotation_blend: str = "slerp") -> Poses:
        """The poses of a clip at each of ``times`` ((T,) finite seconds, any order, clamped like
        ``pose``) in one compiled call: a ``Poses`` of T frames, frame i equal to
        ``self.pose(clip, times[i])``; ``cgaskin.skin(rig, poses)`` skins them all ((T, n, 3))."""
        return Poses.from_clip(self.skeleton, self.clips[self.clip_index(clip)], times, rotation_blend)

    def with_clips(self, *clips: Clip) -> "Rig":
        """A new rig with ``clips`` added after its own (names must stay unique)."""
        names = [c.name for c in self.clips]
        for clip in clips:
            if not isinstance(clip, Clip):
                raise InvalidInputError(f"clips must be cgaskin.Clip objects, got {type(clip).__name__}")
            if clip.name in names:
                raise InvalidInputError(f"the rig already has a clip named {clip.name!r}")
            bad = [c.node for c in clip.channels if not 0 <= c.node < self.skeleton.n_nodes]
            if bad:
                raise InvalidInputError(f"clip {clip.name!r} animates node {bad[0]}, but the skeleton has "
                                        f"{self.skeleton.n_nodes} nodes")
            names.append(clip.name)
        return replace(self, clips=list(self.clips) + list(clips))

    def with_mesh(self, vertices, faces, joints, weights, attributes=None) -> "Rig":
        """A new rig with the same skeleton and clips and another mesh."""
        return replace(self, vertices=vertices, faces=faces, joints=joints, weights=weights,
                       attributes={} if attributes is None else attributes)
