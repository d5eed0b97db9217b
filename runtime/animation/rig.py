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
from functools import cached_property

import numpy as np

from ..errors import InvalidInputError
from ..tolerances import tol

INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")
CHANNEL_PATHS = {"translation": 3, "rotation": 4, "scale": 3}


@dataclass(frozen=True)
class Channel:
    """One animated property of one node.

    node : int, index into ``Skeleton.names``
    path : "translation" | "rotation" | "scale"
    interpolation : "STEP" | "LINEAR" | "CUBICSPLINE"
    times : (k,) float64, strictly increasing seconds
    values : (k, c) float64 for STEP/LINEAR, (k, 3, c) for CUBICSPLINE (in-tangent, value,
        out-tangent), with c = 3 for translation/scale and 4 (x, y, z, w) for rotation
    """

    node: int
    path: str
    interpolation: str
    times: np.ndarray
    values: np.ndarray


@dataclass(frozen=True)
class Clip:
    """A named animation: a set of channels. ``duration`` is the last key time."""

    name: str
    channels: tuple[Channel, ...]

    @property
    def duration(self) -> float:
        return max((float(c.times[-1]) for c in self.channels), default=0.0)


@dataclass(frozen=True)
class Skeleton:
    """Node hierarchy and bones.

    names : list[str], (j,) node names, unique
    parents : (j,) int64, parent node index or -1 for roots; parents[i] < i
    rest_translations : (j, 3) float64
    rest_rotations : (j, 4) float64 unit quaternions (x, y, z, w)
    rest_scales : (j, 3) float64
    rest_matrices : (j, 4, 4) float64 exact local matrices (T @ R @ S for TRS nodes)
    bone_nodes : (b,) int64 node index of each bone
    inverse_bind : (b, 4, 4) float64 inverse bind matrix of each bone
    """

    names: list
    parents: np.ndarray
    rest_translations: np.ndarray
    rest_rotations: np.ndarray
    rest_scales: np.ndarray
    rest_matrices: np.ndarray
    bone_nodes: np.ndarray
    inverse_bind: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.names)

    @property
    def n_bones(self) -> int:
        return len(self.bone_nodes)

    @cached_property
    def inverse_bind_rows(self) -> np.ndarray:
        """(b, 12) C-contiguous top 3x4 rows of the inverse bind matrices (checked affine once)."""
        ibm = np.asarray(self.inverse_bind, dtype=np.float64)
        if not np.allclose(ibm[:, 3, :], [0, 0, 0, 1], atol=tol.affine_row):
            raise InvalidInputError("inverse bind matrices must be affine (last row 0 0 0 1)")
        return np.ascontiguousarray(ibm[:, :3, :].reshape(-1, 12))

    def node_index(self, joint) -> int:
        """Index of a node given by name or index; a clear error lists the valid names."""
        if isinstance(joint, (int, np.integer)):
            if not -self.n_nodes <= joint < self.n_nodes:
                raise InvalidInputError(
                    f"joint index {joint} out of range: the skeleton has {self.n_nodes} nodes")
            return int(joint) % self.n_nodes
        try:
            return self.names.index(joint)
        except ValueError:
            raise InvalidInputError(
                f"unknown joint {joint!r}; valid joints: {', '.join(map(repr, self.names))}") from None


@dataclass(frozen=True)
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
        from .pose import Pose
        return Pose.rest(self.skeleton)

    def bind_pose(self):
        """The pose whose skinning returns ``vertices`` unchanged: every bone's global transform is
        the inverse of its inverse bind matrix (differs from the rest pose in some files)."""
        from .pose import Pose
        return Pose.bind(self.skeleton)

    def pose(self, clip=0, time: float = 0.0, rotation_blend: str = "slerp"):
        """The pose of a clip (name or index) at ``time`` seconds, glTF sampler semantics; rotations
        interpolate as rotors (``"slerp"``: geodesic, as glTF; ``"linear"``: normalised blend)."""
        from .pose import Pose
        return Pose.from_clip(self.skeleton, self.clips[self.clip_index(clip)], time, rotation_blend)

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
