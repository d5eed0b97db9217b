"""Poses: the local transform of every skeleton node for one frame, as versors.

A node whose local transform is a similarity (rotation, translation, positive uniform scale) holds a
versor T R D; composition along the hierarchy is the geometric product (generated kernel). A node
whose transform is not a similarity (non-uniform scale, a matrix with shear) keeps its exact matrix,
and so do its descendants' globals: nothing is approximated (design.md §4).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared.checks import float_array
from .._shared.frozen import kernel_array
from .._shared.jit import B1, F2, F3, I1, callee, helper, kernel
from ..algebra import versor
from ..algebra.transforms import matrix_to_trs, trs_matrix
from ..errors import InvalidInputError
from ..generated.kernels import gp_versor_versor, versor_to_affine
from ..tolerances import tol
from .clip import Channel, Clip
from .sampling import sample_pose, shear_nodes
from .skeleton import Skeleton

FRAMES = ("parent", "local")


@dataclass(frozen=True, eq=False)
class Pose:
    """The local transform of every node of a skeleton for one frame; edits return new poses.

    Parameters
    ----------
    skeleton : Skeleton
        The nodes the pose moves.
    versors : (j, 12) float64
        The local versor of each similarity node (identity elsewhere).
    matrices : (j, 4, 4) float64
        The exact local matrix of each node.
    similar : (j,) bool
        Whether the node's local transform is a similarity held by ``versors``.

    Examples
    --------
    >>> bent = cgaskin.capsule_arm().rest_pose().rotate("elbow", [0, 0, 1], np.pi / 2)
    >>> bent.global_matrices()[2, :3, 3]                    # the wrist, turned up about the elbow
    array([1., 1., 0.])
    """

    skeleton: Skeleton
    versors: np.ndarray
    matrices: np.ndarray
    similar: np.ndarray

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def from_trs(cls, skeleton: Skeleton, translations, rotations, scales, exact_matrices=None):
        """A pose from per-node translation, rotation and scale.

        Parameters
        ----------
        skeleton : Skeleton
            The nodes.
        translations, rotations, scales : (j, 3), (j, 4), (j, 3) float64
            Local TRS of each node, rotations as quaternions (x, y, z, w).
        exact_matrices : list of (4, 4) float64 or None, optional
            Per node, a matrix that overrides a TRS that is only an approximation (shear).

        Returns
        -------
        Pose
        """
        t = np.asarray(translations, dtype=np.float64)
        q = np.asarray(rotations, dtype=np.float64)
        s = np.asarray(scales, dtype=np.float64)
        j = skeleton.n_nodes
        exact = [None] * j if exact_matrices is None else exact_matrices
        overridden = np.array([m is not None for m in exact], dtype=bool)
        # a versor holds the node when its scale is uniform and positive (T R D); else a matrix
        similar = (s[:, 0] == s[:, 1]) & (s[:, 0] == s[:, 2]) & (s[:, 0] > 0) & ~overridden
        versors = np.tile(versor.identity(), (j, 1))
        if similar.any():
            versors[similar] = versor.compose(versor.translator(t[similar]), versor.rotor_from_quaternion(q[similar]),
                                              versor.dilator(s[similar, 0]))
        matrices = trs_matrix(t, q, s)
        for i in np.flatnonzero(overridden):
            matrices[i] = exact[i]
        return cls(skeleton, versors, matrices, similar)

    @classmethod
    def rest(cls, skeleton: Skeleton) -> "Pose":
        """The rest (node) pose stored in the file.

        Parameters
        ----------
        skeleton : Skeleton
            The nodes, with their rest transforms.

        Returns
        -------
        Pose
        """
        exact = shear_nodes(skeleton)
        return cls.from_trs(skeleton, skeleton.rest_translations, skeleton.rest_rotations,
                            skeleton.rest_scales, exact)

    @classmethod
    def bind(cls, skeleton: Skeleton) -> "Pose":
        """The pose whose skinning returns the stored vertices: each bone's global transform is
        inverse(inverse_bind), as exact matrices (need not be similarities); other nodes keep their rest.

        Parameters
        ----------
        skeleton : Skeleton
            The nodes and bones.

        Returns
        -------
        Pose
        """
        n = skeleton.n_nodes
        globals_ = np.empty((n, 4, 4))
        bind_of = {}
        for b, node in enumerate(skeleton.bone_nodes):
            bind_of.setdefault(int(node), np.linalg.inv(skeleton.inverse_bind[b]))
        local = skeleton.rest_matrices.copy()
        for i, p in enumerate(skeleton.parents):
            parent = np.eye(4) if p < 0 else globals_[p]
            if i in bind_of:
                globals_[i] = bind_of[i]
                local[i] = np.linalg.solve(parent, bind_of[i])
            else:
                globals_[i] = parent @ local[i]
        return cls(skeleton, np.tile(versor.identity(), (n, 1)), local, np.zeros(n, dtype=bool))

    @classmethod
    def from_clip(cls, skeleton: Skeleton, clip: Clip, time: float, rotation_blend: str = "slerp") -> "Pose":
        """The pose of a clip at a time, glTF sampler semantics, in one compiled call (``sampling.py``).

        Parameters
        ----------
        skeleton : Skeleton
            The nodes.
        clip : Clip
            The animation; properties it does not animate keep their rest values.
        time : float
            Finite seconds; before the first key clamps to the first key, after the last to the last.
        rotation_blend : {"slerp", "linear"}, optional
            Rotations by slerp on the shorter arc, or by the normalised linear blend.

        Returns
        -------
        Pose
        """
        return cls._of_fields(skeleton, *sample_pose(skeleton, clip, time, rotation_blend))

    @classmethod
    def _of_fields(cls, skeleton: Skeleton, versors, matrices, similar) -> "Pose":
        """A pose of fields a kernel has just made for it (owned by nobody else): the constructor,
        without the frozen dataclass's four ``object.__setattr__`` (a tenth of a sampled frame)."""
        pose = object.__new__(cls)
        fields = pose.__dict__
        fields["skeleton"], fields["versors"], fields["matrices"], fields["similar"] = \
            skeleton, versors, matrices, similar
        return pose

    # -- edits (each returns a new Pose) --------------------------------------------------------
    def _edit(self, joint, what: str, left=None, right=None) -> "Pose":
        """local' = left · local · right (versors), on the versor or, for matrix nodes, the matrix.
        ``what`` names the edit for the error when the result is not finite."""
        i = self.skeleton.node_index(joint)
        # large but finite values make a finite pose (the versor check's |V|² may overflow on the
        # way, harmlessly); a transform float64 cannot hold is the caller's to fix, not a warning
        too_large = (f"{what}: the transform of joint {self.skeleton.names[i]!r} would overflow float64 "
                     f"(or, as a versor, leave the scales [{versor.SCALE_RANGE[0]:g}, "
                     f"{versor.SCALE_RANGE[1]:g}] it holds); give a smaller value")
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                versors, matrices = self._edited(i, left, right)
        except InvalidInputError:       # the inputs are checked: only the composed result can fail
            raise InvalidInputError(too_large) from None
        if not (np.isfinite(versors[i]).all() and np.isfinite(matrices[i]).all()):
            raise InvalidInputError(too_large)
        return Pose(self.skeleton, versors, matrices, self.similar)

    def _edited(self, i: int, left, right) -> tuple:
        versors, matrices = self.versors.copy(), self.matrices.copy()
        if self.similar[i]:
            parts = [p for p in (left, versors[i], right) if p is not None]
            versors[i] = versor.compose(*parts)
            matrices[i] = versor.to_matrix(versors[i])
        else:
            m = matrices[i]
            if left is not None:
                m = versor.to_matrix(left) @ m
            if right is not None:
                m = m @ versor.to_matrix(right)
            matrices[i] = m
        return versors, matrices

    def rotate(self, joint, axis, angle, frame: str = "parent") -> "Pose":
        """The pose with a joint rotated about an axis through its origin.

        Parameters
        ----------
        joint : str or int
            The node's name or index.
        axis : (3,) array_like
            Rotation axis, any nonzero length.
        angle : float
            Radians, right-handed about ``axis``.
        frame : {"parent", "local"}, optional
            The frame ``axis`` is given in: the parent's or the joint's own.

        Returns
        -------
        Pose
        """
        if frame not in FRAMES:
            raise InvalidInputError(f"frame must be one of {FRAMES}, got {frame!r}")
        rot = versor.rotor(axis, angle)
        what = f"rotate({joint!r}, ...)"
        if frame == "local":
            return self._edit(joint, what, right=rot)
        pivot = self.matrices[self.skeleton.node_index(joint)][:3, 3]
        with np.errstate(over="ignore", invalid="ignore"):      # (checked in _edit)
            left = versor.compose(versor.translator(pivot), rot, versor.translator(-pivot))
        return self._edit(joint, what, left=left)

    def translate(self, joint, vector) -> "Pose":
        """The pose with a joint moved in its parent's frame.

        Parameters
        ----------
        joint : str or int
            The node's name or index.
        vector : (3,) array_like
            The translation.

        Returns
        -------
        Pose
        """
        vector = float_array(vector, "vector", 3)
        return self._edit(joint, f"translate({joint!r}, {vector.tolist()})", left=versor.translator(vector))

    def dilate(self, joint, scale) -> "Pose":
        """The pose with a joint's subtree scaled uniformly about the joint's origin.

        Parameters
        ----------
        joint : str or int
            The node's name or index.
        scale : float
            The factor, in ``versor.SCALE_RANGE`` ([1e-12, 1e12]), else InvalidInputError.

        Returns
        -------
        Pose
        """
        return self._edit(joint, f"dilate({joint!r}, {scale!r})", right=versor.dilator(scale))

    # -- evaluation ----------------------------------------------------------------------------
    def bone_affines(self) -> np.ndarray:
        """Each bone's skinning map G[bone_nodes[b]] @ inverse_bind[b], for the blend loop.

        Returns
        -------
        (b, 12) float64
            Row-major 3x4 maps.
        """
        sk = self.skeleton
        out = np.empty((sk.n_bones, 12))
        # (the writeable buffers behind the skeleton's read-only arrays: the kernel's one compiled type)
        _bone_affines(kernel_array(sk.parents), self.versors, self.matrices, self.similar,
                      kernel_array(sk.bone_nodes), sk.inverse_bind_rows, out)
        return out

    def global_matrices(self) -> np.ndarray:
        """The global transform of every node.

        Returns
        -------
        (j, 4, 4) float64
        """
        sk = self.skeleton
        out = np.empty((sk.n_nodes, 12))
        ident = np.zeros((sk.n_nodes, 12))
        ident[:, [0, 5, 10]] = 1.0
        _bone_affines(kernel_array(sk.parents), self.versors, self.matrices, self.similar,
                      np.arange(sk.n_nodes), ident, out)
        m = np.zeros((sk.n_nodes, 4, 4))
        m[:, :3, :] = out.reshape(-1, 3, 4)
        m[:, 3, 3] = 1.0
        return m


def clip_from_poses(name: str, times, poses, interpolation: str = "LINEAR") -> Clip:
    """A clip whose keyframes are poses: poses made on the fly become an animation (``save``
    exports it).

    Parameters
    ----------
    name : str
        The clip's name.
    times : (k,) float
        Key times, strictly increasing seconds.
    poses : sequence of k Pose
        The keys, of one skeleton.
    interpolation : {"LINEAR", "STEP"}, optional
        LINEAR: rotations by slerp, translations and scales linearly.

    Returns
    -------
    Clip
        TRS channels for each node that leaves its rest transform in some key (InvalidInputError for
        mismatched ``times``/``poses``, poses of other skeletons, a transform with shear).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm(); rest = arm.rest_pose()
    >>> bend = cgaskin.clip_from_poses("bend", [0.0, 1.0], [rest, rest.rotate("elbow", [0, 0, 1], 1.0)])
    >>> arm.with_clips(bend).pose("bend", 0.5).global_matrices()[2, :3, 3].round(3)
    array([1.878, 0.479, 0.   ])
    """
    if not isinstance(name, str) or not name:
        raise InvalidInputError(f"name must be a non-empty string, got {name!r}")
    if interpolation not in ("LINEAR", "STEP"):
        raise InvalidInputError(f"interpolation must be 'LINEAR' or 'STEP', got {interpolation!r}")
    times = float_array(times, "times", ndim=1)
    poses = list(poses)
    if len(times) == 0 or len(times) != len(poses):
        raise InvalidInputError(f"times and poses must be non-empty and of one length, got {len(times)} "
                                f"times and {len(poses)} poses")
    if np.any(np.diff(times) <= 0):
        raise InvalidInputError(f"times must be strictly increasing, got {times.tolist()}")
    for k, pose in enumerate(poses):
        if not isinstance(pose, Pose):
            raise InvalidInputError(f"poses[{k}] must be a cgaskin.Pose, got {type(pose).__name__}")
        if pose.skeleton is not poses[0].skeleton and list(pose.skeleton.names) != list(poses[0].skeleton.names):
            raise InvalidInputError(f"poses[{k}] belongs to another skeleton than poses[0]")
    skeleton = poses[0].skeleton
    local = np.stack([pose.matrices for pose in poses])                 # (k, j, 4, 4)
    rest = Pose.rest(skeleton).matrices
    size = np.maximum(1.0, np.abs(local).max(axis=(0, 2, 3)))
    changed = np.abs(local - rest).max(axis=(0, 2, 3)) > tol.pose_change * size
    channels = []
    for node in np.flatnonzero(changed):
        trs = [matrix_to_trs(m) for m in local[:, node]]
        t, q, s = (np.array(column) for column in zip(*trs))
        rebuilt = trs_matrix(t, q, s)
        bad = np.abs(rebuilt - local[:, node]).max(axis=(1, 2)) > tol.trs_rebuild * size[node]
        if bad.any():
            raise InvalidInputError(f"poses[{int(np.argmax(bad))}]: node {skeleton.names[node]!r} has a "
                                    f"sheared transform, which an animation channel cannot hold")
        for k in range(1, len(q)):                  # one hemisphere, for readers that blend naively
            if q[k] @ q[k - 1] < 0:
                q[k] = -q[k]
        for path, values in (("translation", t), ("rotation", q), ("scale", s)):
            channels.append(Channel(node=int(node), path=path, interpolation=interpolation,
                                    times=times.copy(), values=values))
    return Clip(name=name, channels=tuple(channels))


@helper
def _compose_affine(a, b):
    """Row-major 3x4 a ∘ 3x4 b (both as (12,) arrays), as (12,)."""
    out = np.empty(12)
    for r in range(3):
        for c in range(4):
            acc = a[4 * r + 3] if c == 3 else 0.0
            for k in range(3):
                acc += a[4 * r + k] * b[4 * k + c]
            out[4 * r + c] = acc
    return out


@kernel((I1, F2, F3, B1, I1, F2, F2), cost=0.3, fused=True)
def _bone_affines(parents, versors, matrices, similar, bone_nodes, ibm, out):
    """Each bone's 3x4 map G @ IBM of one pose (``bone_affines_into``)."""
    bone_affines_into(parents, versors, matrices, similar, bone_nodes, ibm, out)


# compiled ahead on its own, then loaded by the kernels of one pose and of many (poses.py)
@callee((I1, F2, F3, B1, I1, F2, F2), cost=2.5)
def bone_affines_into(parents, versors, matrices, similar, bone_nodes, ibm, out):
    """Globals along the hierarchy (versor products while every ancestor is a similarity, exact
    matrices below any that is not), then each bone's 3x4 map G @ IBM."""
    n = parents.shape[0]
    gv = np.empty((n, 12))
    ga = np.empty((n, 12))
    gsim = np.zeros(n, dtype=np.bool_)
    local = np.empty(12)
    for i in range(n):
        p = parents[i]
        if similar[i] and (p < 0 or gsim[p]):
            if p < 0:
                for c in range(12):
                    gv[i, c] = versors[i, c]
            else:
                g = gp_versor_versor(gv[p], versors[i])
                for c in range(12):
                    gv[i, c] = g[c]
            a = versor_to_affine(gv[i])
            for c in range(12):
                ga[i, c] = a[c]
            gsim[i] = True
        else:
            for r in range(3):
                for c in range(4):
                    local[4 * r + c] = matrices[i, r, c]
            a = local if p < 0 else _compose_affine(ga[p], local)
            for c in range(12):
                ga[i, c] = a[c]
    for b in range(bone_nodes.shape[0]):
        a = _compose_affine(ga[bone_nodes[b]], ibm[b])
        for c in range(12):       # a loop: numba's row assignment compiles a formatted error message
            out[b, c] = a[c]

