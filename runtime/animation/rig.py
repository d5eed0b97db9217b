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

A rig is checked where it is made (constructor, ``with_mesh``, ``dataclasses.replace``) by
``validate.check_mesh``, the rule loaders and ``save`` apply too, and is immutable: its arrays (and
its skeleton's) are read-only copies, its attributes a read-only dict, because values derived from
it are cached per rig (``_shared.cache``) and an edit in place would leave them stale. To change a
mesh, make a new rig: ``rig.with_mesh(edited copies...)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .._shared.checks import float_array, item_index, real_number
from .._shared.frozen import FrozenDict, frozen
from ..errors import InvalidInputError
from .clip import CHANNEL_PATHS, INTERPOLATIONS, Channel, Clip
from .pose import Pose
from .poses import Poses
from .sampling import frame_sampler, sample_frame
from .skeleton import Skeleton
from .validate import check_mesh

_CLIP_KEYS = (str, int)       # (not bool: True would find the sampler of clip 1)

#: the whole data model in one import
__all__ = ["Rig", "Skeleton", "Clip", "Channel", "INTERPOLATIONS", "CHANNEL_PATHS"]


@dataclass(frozen=True, eq=False)
class Rig:
    """A skinned triangle mesh, immutable: every array is a read-only copy of what it was made from.

    Made from any arrays that ``check_mesh`` accepts (other real dtypes, 1 to 3 or more than 4
    influences, rows not summing to 1): they are normalised as it does, with the same warnings.

    Parameters
    ----------
    vertices : (n, 3) float64
        Bind-pose positions, finite.
    faces : (m, 3) int64
        Vertex indices in [0, n), counter-clockwise.
    joints : (n, 4) int64
        Bone indices in [0, skeleton.n_bones) (unused slots hold 0 with weight 0).
    weights : (n, 4) float64
        Finite, >= 0, each row summing to 1 (at least one weight > 0 per vertex).
    skeleton : Skeleton
        The nodes and bones the joints index.
    clips : list of Clip, optional
        The animations.
    attributes : dict, optional
        Name -> (n, ...) real per-vertex data carried through cut, tear and export (glTF names:
        "NORMAL", "TEXCOORD_0"), finite, dtype kept; held as a read-only dict.
    name : str, optional
        The model's name (messages and saved files name it).

    Raises
    ------
    InvalidInputError
        Names the first bad row and its value: a non-finite vertex, a face outside the vertices, a
        negative or non-finite weight, a vertex without any weight, a weighted joint outside the
        skeleton's bones, an attribute with the wrong row count or non-finite values.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> rig = cgaskin.Rig(arm.vertices, arm.faces, arm.joints, arm.weights, arm.skeleton, name="arm")
    >>> rig.n_vertices, rig.n_faces, rig.clips
    (690, 1376, [])
    >>> rig.vertices.flags.writeable
    False
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    skeleton: Skeleton
    clips: list = field(default_factory=list)
    attributes: dict = field(default_factory=dict)
    name: str = "rig"

    def __post_init__(self):
        if not isinstance(self.skeleton, Skeleton):
            raise InvalidInputError(f"skeleton must be a cgaskin.Skeleton, got {type(self.skeleton).__name__}")
        # (check_mesh works on copies: the maker's arrays are never modified, nor held)
        arrays = check_mesh(self.vertices, self.faces, self.joints, self.weights,
                            n_bones=self.skeleton.n_bones, source=self.name)
        for name, values in zip(("vertices", "faces", "joints", "weights"), arrays):
            object.__setattr__(self, name, frozen(values))
        object.__setattr__(self, "attributes", _checked_attributes(self.attributes, len(arrays[0])))

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    def clip_index(self, clip) -> int:
        """The index of a clip given by name or index.

        Parameters
        ----------
        clip : str or int
            A clip name, or an index into ``clips``.

        Returns
        -------
        int

        Raises
        ------
        InvalidInputError
            An unknown clip (the message lists the rig's clips).
        """
        if type(clip) is int and 0 <= clip < len(self.clips):       # the common case, per frame
            return clip
        if type(clip) is str:                # by name, per frame: a dict, checked (``clips`` is a list)
            index = self._clip_indices.get(clip, -1)
            if 0 <= index < len(self.clips) and self.clips[index].name == clip:
                return index
        index = item_index(clip, len(self.clips), "clip", f"the rig has {len(self.clips)} clips")
        if index is not None:
            return index
        names = [c.name for c in self.clips]
        if clip in names:
            return names.index(clip)
        raise InvalidInputError(f"unknown clip {clip!r}; valid clips: {', '.join(map(repr, names)) or 'none'}")

    @cached_property
    def _clip_indices(self) -> dict:
        """Clip name -> index of the first clip of that name, made on first use."""
        indices = {}
        for i, c in enumerate(self.clips):
            indices.setdefault(c.name, i)
        return indices

    def rest_pose(self):
        """The rest (node) pose of the skeleton.

        Returns
        -------
        Pose
        """
        return Pose.rest(self.skeleton)

    def bind_pose(self):
        """The pose whose skinning returns ``vertices`` unchanged.

        Every bone's global transform is the inverse of its inverse bind matrix (differs from the
        rest pose in some files).

        Returns
        -------
        Pose
        """
        return Pose.bind(self.skeleton)

    def pose(self, clip=0, time: float = 0.0, rotation_blend: str = "slerp") -> Pose:
        """The pose of a clip at a time, with glTF's sampler semantics, in one compiled call.

        Parameters
        ----------
        clip : str or int, optional
            The clip's name or index.
        time : float, optional
            Seconds; a time before the first key or after the last clamps to that key (no error).
        rotation_blend : {"slerp", "linear"}, optional
            Rotations by slerp on the shorter arc (as glTF), or by the normalised linear blend.

        Returns
        -------
        Pose

        Raises
        ------
        InvalidInputError
            An unknown clip (the message lists the rig's clips), a time that is not a finite number.

        Examples
        --------
        >>> pose = cgaskin.capsule_arm().pose("wave", 0.5)
        >>> pose.versors.shape                                  # one versor per node
        (3, 12)
        """
        key = (clip, rotation_blend) if type(clip) in _CLIP_KEYS and type(rotation_blend) is str else None
        kept = self._samplers.get(key)
        # (``clips`` is a list: the clip kept for this name or index must still be the rig's)
        if kept is None or not (kept[0] < len(self.clips) and self.clips[kept[0]] is kept[1].clip):
            index = self.clip_index(clip)       # (the clip's first frame: checked and made ready)
            kept = (index, frame_sampler(self.skeleton, self.clips[index], rotation_blend))
            if key is not None:
                self._samplers[key] = kept
        t = time if type(time) is float and math.isfinite(time) else real_number(time, "time")
        return Pose._of_fields(self.skeleton, *sample_frame(kept[1], t))

    @cached_property
    def _samplers(self) -> dict:
        """(clip name or index as the caller gave it, rotation blend) -> (clip index, the clip made
        ready to sample on the rig's skeleton): a frame's call then pays one lookup."""
        return {}

    def poses(self, clip=0, times=(0.0,), rotation_blend: str = "slerp") -> Poses:
        """The poses of a clip at many times, in one compiled call.

        Parameters
        ----------
        clip : str or int, optional
            The clip's name or index.
        times : (T,) array_like of float, optional
            Finite seconds, any order, clamped like ``pose``.
        rotation_blend : {"slerp", "linear"}, optional
            As ``pose``.

        Returns
        -------
        Poses
            T frames, frame i equal to ``self.pose(clip, times[i])``.

        Examples
        --------
        >>> arm = cgaskin.capsule_arm()
        >>> cgaskin.skin(arm, arm.poses("wave", np.linspace(0.0, 2.0, 5))).shape
        (5, 690, 3)
        """
        return Poses.from_clip(self.skeleton, self.clips[self.clip_index(clip)], times, rotation_blend)

    def with_clips(self, *clips: Clip) -> "Rig":
        """A new rig with more clips, added after its own.

        Parameters
        ----------
        *clips : Clip
            The clips to add; names must stay unique, channels must animate the skeleton's nodes.

        Returns
        -------
        Rig
        """
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

    def __reduce__(self):
        # unpickled (a Dask worker, a saved session) with read-only arrays again; they were checked
        return Rig._of_checked, (self.vertices, self.faces, self.joints, self.weights, self.skeleton, self.clips,
                                dict(self.attributes), self.name)

    @classmethod
    def _of_checked(cls, vertices, faces, joints, weights, skeleton, clips=(), attributes=None,
                   name: str = "rig") -> "Rig":
        """A rig of arrays that cgaskin's own operations made from checked rigs (a cut's halves, a torn
        mesh, a session's snapshot), frozen but not checked again: those operations keep every rule of
        ``check_mesh`` (their property tests check it), and checking would cost more than the cut.
        Users make rigs with the constructor or ``with_mesh``."""
        rig = object.__new__(cls)
        for name_, values in (("vertices", vertices), ("faces", faces), ("joints", joints), ("weights", weights)):
            object.__setattr__(rig, name_, frozen(values))
        for name_, value in (("skeleton", skeleton), ("clips", list(clips)), ("name", name),
                             ("attributes", FrozenDict({k: frozen(np.asarray(v)) for k, v in
                                                        ({} if attributes is None else attributes).items()}))):
            object.__setattr__(rig, name_, value)
        return rig

    def _with_checked_mesh(self, vertices, faces, joints, weights, attributes=None) -> "Rig":
        """``with_mesh`` for cgaskin's own operations (``_of_checked``)."""
        return Rig._of_checked(vertices, faces, joints, weights, self.skeleton, self.clips, attributes, self.name)

    def with_mesh(self, vertices, faces, joints, weights, attributes=None) -> "Rig":
        """A new rig with the same skeleton and clips and another mesh, checked and copied as the
        constructor does (``InvalidInputError`` names the first bad row).

        Parameters
        ----------
        vertices : (n, 3) float64
            Bind-pose positions.
        faces : (m, 3) int64
            Vertex indices, counter-clockwise.
        joints : (n, 4) int64
            Bone indices.
        weights : (n, 4) float64
            Bone weights, each row summing to 1.
        attributes : dict, optional
            Per-vertex data (default: none).

        Returns
        -------
        Rig
        """
        return replace(self, vertices=vertices, faces=faces, joints=joints, weights=weights,
                       attributes={} if attributes is None else attributes)


def _checked_attributes(attributes, n: int) -> FrozenDict:
    """Read-only copies of per-vertex attributes: real numbers (dtype kept), finite, ``n`` rows."""
    if not hasattr(attributes, "items"):
        raise InvalidInputError(f"attributes must be a dict name -> (n, k) array, got {type(attributes).__name__}")
    out = {}
    for name, values in attributes.items():
        what = f"attribute {name!r}"
        values = np.asarray(values)
        if values.dtype.kind not in "iub":           # NaN, inf, strings, complex refused, naming where
            checked = float_array(values, what)
            values = values if values.dtype.kind == "f" else checked
        if values.ndim == 0 or len(values) != n:
            rows = "a scalar" if values.ndim == 0 else f"{len(values)} rows"
            raise InvalidInputError(f"{what} has {rows} for {n} vertices; give one row per vertex")
        out[name] = frozen(np.array(values, order="C"))
    return FrozenDict(out)
