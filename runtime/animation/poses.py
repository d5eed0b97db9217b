"""Many poses of one skeleton at once: a clip sampled at T times (``Rig.poses``), their bone maps in
one compiled call, and ``cgaskin.skin(rig, poses)`` for every frame."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared.frozen import kernel_array
from .._shared.jit import B2, F2, F3, F4, I1, kernel
from ..errors import InvalidInputError
from .clip import Clip
from .pose import Pose, bone_affines_into
from .sampling import sample_poses
from .skeleton import Skeleton


@dataclass(frozen=True, eq=False)
class Poses:
    """T poses of one skeleton: the fields of ``Pose`` with a leading frame axis.

    ``len(poses)`` is T, ``poses[i]`` the ``Pose`` of frame i (a copy: edit it like any pose),
    ``poses[a:b]`` a ``Poses`` of those frames; iterating gives the frames' poses in order.

    Parameters
    ----------
    skeleton : Skeleton
        The nodes the poses move.
    times : (T,) float64
        Seconds of each frame in its clip.
    versors : (T, j, 12) float64
        Each frame's local versors (``Pose.versors``).
    matrices : (T, j, 4, 4) float64
        Each frame's exact local matrices.
    similar : (T, j) bool
        Whether each node of each frame is a similarity held by ``versors``.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> poses = arm.poses("wave", [0.0, 0.5, 1.0])
    >>> len(poses), poses.versors.shape, type(poses[1]).__name__
    (3, (3, 3, 12), 'Pose')
    >>> cgaskin.skin(arm, poses).shape                      # every frame at once
    (3, 690, 3)
    """

    skeleton: Skeleton
    times: np.ndarray
    versors: np.ndarray
    matrices: np.ndarray
    similar: np.ndarray

    @classmethod
    def from_clip(cls, skeleton: Skeleton, clip: Clip, times, rotation_blend: str = "slerp") -> "Poses":
        """The poses of a clip at many times, sampled in one compiled call.

        Parameters
        ----------
        skeleton : Skeleton
            The nodes.
        clip : Clip
            The animation.
        times : (T,) array_like of float
            Finite seconds, in any order; each clamps to the keys as glTF says.
        rotation_blend : {"slerp", "linear"}, optional
            As ``Pose.from_clip``.

        Returns
        -------
        Poses
            Frame i equals ``Pose.from_clip(skeleton, clip, times[i], rotation_blend)`` exactly.
        """
        return cls(skeleton, *sample_poses(skeleton, clip, times, rotation_blend))

    def __len__(self) -> int:
        return len(self.times)

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def __getitem__(self, index):
        if isinstance(index, slice):
            return Poses(self.skeleton, self.times[index], self.versors[index], self.matrices[index],
                         self.similar[index])
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
            raise InvalidInputError(f"poses are indexed by a frame number or a slice, got {index!r}")
        if not -len(self) <= index < len(self):
            raise InvalidInputError(f"frame {index} out of range: there are {len(self)} poses")
        return Pose(self.skeleton, self.versors[index].copy(), self.matrices[index].copy(),
                    self.similar[index].copy())

    def bone_affines(self) -> np.ndarray:
        """Every frame's bone maps G[bone_nodes[b]] @ inverse_bind[b], in one compiled call.

        Returns
        -------
        (T, b, 12) float64
            Row-major 3x4 maps; frame i equals ``self[i].bone_affines()`` exactly.
        """
        sk = self.skeleton
        out = np.empty((len(self), sk.n_bones, 12))
        # slices of a frame range need not be contiguous arrays of their own: the kernel takes C arrays
        # (and the writeable buffers behind the skeleton's read-only arrays: the kernel's one type)
        _bone_affines_frames(kernel_array(sk.parents), np.ascontiguousarray(self.versors),
                             np.ascontiguousarray(self.matrices), np.ascontiguousarray(self.similar),
                             kernel_array(sk.bone_nodes), sk.inverse_bind_rows, out)
        return out


@kernel((I1, F3, F4, B2, I1, F2, F3), cost=0.3, fused=True)
def _bone_affines_frames(parents, versors, matrices, similar, bone_nodes, ibm, out):
    """``bone_affines_into`` for each frame: versors (T, j, 12), matrices (T, j, 4, 4), similar (T, j)
    -> out (T, B, 12)."""
    for f in range(versors.shape[0]):
        bone_affines_into(parents, versors[f], matrices[f], similar[f], bone_nodes, ibm, out[f])
