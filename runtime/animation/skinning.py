"""Linear blend skinning through the hoisted CGA kernels.

Per frame: each bone's versor becomes its 3x4 affine form once (``versor_to_affine``, the per-bone
half of the hoisted sandwich), then one loop over vertices blends the affine coefficients by the
weights and applies them (``skin_blend``). That equals Σ_k w_k down(V_k up(x) Ṽ_k) exactly, because
the per-vertex kernel is linear in the per-bone coefficients (the build checks it).
"""
from __future__ import annotations

import numpy as np

from .._shared.cache import check_read_only
from .._shared.checks import float_array, index_array
from .._shared.frozen import kernel_array
from .._shared.jit import F2, F3, I2, WIDE, kernel, precompiled
from .._shared.memory_budget import require_memory
from ..algebra.versor_products import _versor_arg
from ..errors import InvalidInputError
from ..generated import kernels as K
from ..generated.skinning import skin_blend, skin_blend_parallel
from .pose import Pose
from .poses import Poses
from .rig import Rig

# numba's thread pool costs ~10 ms per parallel call on a 2-core machine; below this many vertices
# the serial loop wins (benchmarks/bench_skinning.py measures the crossover).
PARALLEL_THRESHOLD = 100_000

precompiled(skin_blend, (F2, I2, F2, F2, F2), cost=0.4, targets=WIDE)
precompiled(skin_blend_parallel, (F2, I2, F2, F2, F2), cost=1.5, targets=WIDE)


def _mesh_args(rest, joints, weights):
    """Shapes and dtypes only: values (finiteness, index range) are checked inside the blend loop,
    which reports problems without a second pass over the data."""
    rest = np.asarray(rest)
    if rest.dtype != np.float64:
        rest = float_array(rest, "rest")
    weights = np.asarray(weights)
    if weights.dtype not in (np.float32, np.float64):
        weights = float_array(weights, "weights")
    joints = np.asarray(joints)
    if joints.dtype.kind not in "iu":
        joints = index_array(joints, "joints", np.iinfo(np.int64).max)
    if rest.ndim != 2 or rest.shape[1] != 3:
        raise InvalidInputError(f"rest must have shape (n, 3), got {rest.shape}")
    if weights.ndim != 2 or weights.shape[0] != rest.shape[0]:
        raise InvalidInputError(f"weights must have shape ({rest.shape[0]}, k), got {weights.shape}")
    if joints.shape != weights.shape:
        raise InvalidInputError(f"joints shape {joints.shape} must equal weights shape {weights.shape}")
    return rest, np.ascontiguousarray(joints), np.ascontiguousarray(weights)


def _diagnose(rest, joints, weights, affines, bad_joints, bad_weights, bad_values):
    """Name the first bad input after the blend loop reported a problem (the slow path)."""
    if bad_joints:
        index_array(joints, "joints", len(affines))
    for name, arr in (("rest", rest), ("weights", weights), ("affines", affines)):
        float_array(arr, name)
    if bad_weights:
        i, k = np.argwhere(weights < 0)[0]
        raise InvalidInputError(f"weights must be >= 0 (a blend of transforms): vertex {i} has weight "
                                f"{float(weights[i, k])!r} on influence {k} ({bad_weights} negative weights)")
    raise InvalidInputError(f"{bad_values} skinned vertices are not finite; the bone transforms "
                            f"overflow float64")


def skin_affine(rest, joints, weights, affines, parallel=None, out=None) -> np.ndarray:
    """Blend per-bone affine maps: out[i] = Σ_k weights[i,k] (A[joints[i,k]] applied to rest[i]).

    For transforms that are not similarities (bind matrices with non-uniform scale); similarity
    poses can use ``skin_vertices``.

    Parameters
    ----------
    rest : (n, 3) float64
        Rest positions.
    joints : (n, k) int
        Bone index of each influence.
    weights : (n, k) float32 or float64
        Influence weights, >= 0.
    affines : (b, 3, 4) or (b, 12) float64
        Each bone's affine map (row-major 3x4).
    parallel : bool, optional
        Blend on every core; None (default) decides by the vertex count.
    out : (n, 3) float64, optional
        A C-contiguous array to write into (reuse it across frames).

    Returns
    -------
    (n, 3) float64
        The skinned positions (``out`` when given).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> affines = np.tile(np.eye(4)[:3], (3, 1, 1))
    >>> affines[:, 0, 0] = 2.0                              # every bone stretches x by 2
    >>> cgaskin.skin_affine(arm.vertices, arm.joints, arm.weights, affines)[-1]
    array([6.5, 0. , 0. ])
    """
    affines = np.asarray(affines)
    if affines.dtype != np.float64:
        affines = float_array(affines, "affines")
    if affines.ndim not in (2, 3) or affines.shape[1:] not in ((3, 4), (12,)):
        raise InvalidInputError(f"affines must have shape (B, 3, 4) or (B, 12), got {affines.shape}")
    affines = np.ascontiguousarray(affines.reshape(len(affines), 12))
    rest, joints, weights = _mesh_args(rest, joints, weights)
    if out is None:
        out = np.empty_like(rest)
    elif out.shape != rest.shape or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise InvalidInputError(f"out must be a C-contiguous float64 array of shape {rest.shape}")
    if parallel is None:
        parallel = len(rest) >= PARALLEL_THRESHOLD
    bad_joints, bad_weights, bad_values = (skin_blend_parallel if parallel else skin_blend)(
        rest, joints, weights, affines, out)
    if bad_joints or bad_weights or bad_values:
        _diagnose(rest, joints, weights, affines, bad_joints, bad_weights, bad_values)
    return out


def bone_affines(versors) -> np.ndarray:
    """(B, 12) hoisted affine coefficients of (B, 12) versors (the per-bone half of skinning)."""
    versors = _versor_arg(versors, "versors")
    if versors.ndim != 2:
        raise InvalidInputError(f"versors must have shape (B, 12), got {versors.shape}")
    out = np.empty((len(versors), 12))
    K.versor_to_affine_batch(np.ascontiguousarray(versors), out)
    return out


def skin_vertices(rest, joints, weights, versors, parallel=None, out=None) -> np.ndarray:
    """Skin rest positions with one versor per bone: Σ_k w_k down(V_k up(x) Ṽ_k).

    Parameters
    ----------
    rest : (n, 3) float64
        Rest positions.
    joints : (n, k) int
        Bone index of each influence.
    weights : (n, k) float
        Influence weights, >= 0.
    versors : (b, 12) float64
        Each bone's versor (its global transform times its inverse bind).
    parallel : bool, optional
        Blend on every core; None (default) decides by the vertex count.
    out : (n, 3) float64, optional
        A C-contiguous array to write into; the caller's other arrays are not modified.

    Returns
    -------
    (n, 3) float64
        The skinned positions (``out`` when given).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> up = cgaskin.versor.translator(np.tile([0.0, 1.0, 0.0], (3, 1)))      # every bone up by 1
    >>> cgaskin.skin_vertices(arm.vertices, arm.joints, arm.weights, up)[-1]
    array([3.25, 1.  , 0.  ])
    """
    return skin_affine(rest, joints, weights, bone_affines(versors), parallel=parallel, out=out)


def check_pose(rig: Rig, pose, kinds=(Pose,)):
    """``pose`` itself when it is a ``Pose`` (or another of ``kinds``) of ``rig``'s skeleton (that
    object, or one with the same nodes and bones, as a cut or torn rig shares with its original);
    ``InvalidInputError`` if not."""
    if not isinstance(pose, kinds):
        names = " or ".join(f"a cgaskin.{kind.__name__}" for kind in kinds)
        raise InvalidInputError(f"pose must be {names} or None, got {type(pose).__name__}")
    a, b = rig.skeleton, pose.skeleton
    if b is not a and (b.n_nodes != a.n_nodes or list(b.names) != list(a.names)
                       or not np.array_equal(b.bone_nodes, a.bone_nodes)):
        raise InvalidInputError("the pose belongs to another skeleton (its nodes or bones differ from "
                                "the rig's)")
    return pose


def skin(rig: Rig, pose: Pose | Poses | None = None, out=None) -> np.ndarray:
    """The positions of a rig's vertices in a pose (linear blend skinning).

    glTF semantics for every format: Σ_i w_i (G[joint_i] · IBM_i) v; the mesh node's own transform is
    ignored.

    Parameters
    ----------
    rig : Rig
        The model.
    pose : Pose or Poses, optional
        A pose of its skeleton (default: the rest pose), or T frames (``rig.poses(clip, times)``:
        their bone maps and the blend of every frame in one compiled call each).
    out : (n, 3) or (T, n, 3) float64, optional
        A C-contiguous array to write into (reuse it across frames).

    Returns
    -------
    (n, 3) or (T, n, 3) float64
        The skinned positions (``out`` when given).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> cgaskin.skin(arm, arm.pose("wave", 1.0))[-1].round(3)          # the tip, raised
    array([1.  , 2.25, 0.  ])
    """
    pose = rig.rest_pose() if pose is None else check_pose(rig, pose, (Pose, Poses))
    check_read_only(rig)
    if isinstance(pose, Poses):
        return _skin_poses(rig, pose, out)
    # (the writeable buffers behind the rig's read-only arrays: the blend loop's one compiled type)
    return skin_affine(kernel_array(rig.vertices), kernel_array(rig.joints), kernel_array(rig.weights),
                       pose.bone_affines(), out=out)


def _skin_poses(rig: Rig, poses: Poses, out) -> np.ndarray:
    rest, joints, weights = _mesh_args(kernel_array(rig.vertices), kernel_array(rig.joints), kernel_array(rig.weights))
    # one compiled variant: the rig's own arrays are these types already (the loaders make them so)
    joints, weights = np.ascontiguousarray(joints, np.int64), np.ascontiguousarray(weights, np.float64)
    rest = np.ascontiguousarray(rest)
    shape = (len(poses),) + rest.shape
    if out is None:
        # the frames' positions (T, n, 3) and their bone maps (T, B, 12): checked before they are made
        require_memory(len(poses) * (rest.shape[0] * 24 + rig.skeleton.n_bones * 96),
                       f"skin of {len(poses)} frames of {rest.shape[0]} vertices", "skin fewer frames at a time "
                       "(a slice of the poses), or give out=")
        out = np.empty(shape)
    elif out.shape != shape or out.dtype != np.float64 or not out.flags.c_contiguous:
        raise InvalidInputError(f"out must be a C-contiguous float64 array of shape {shape}")
    affines = poses.bone_affines()
    if len(rest) >= PARALLEL_THRESHOLD:          # big meshes: each frame's blend on every core
        for f in range(len(poses)):
            skin_affine(rest, joints, weights, affines[f], parallel=True, out=out[f])
        return out
    if _skin_frames(rest, joints, weights, affines, out):
        for f in range(len(poses)):              # name the first problem (the slow path)
            skin_affine(rest, joints, weights, affines[f], parallel=False, out=out[f])
    return out


@kernel((F2, I2, F2, F3, F3), cost=0.3, fused=True, targets=WIDE)
def _skin_frames(rest, joints, weights, affines, out):
    """``skin_blend`` of every frame: affines (T, B, 12) -> out (T, n, 3); whether any frame reported
    a bad joint index, weight or result."""
    bad = False
    for f in range(affines.shape[0]):
        bad_joints, bad_weights, bad_values = skin_blend(rest, joints, weights, affines[f], out[f])
        bad = bad or bad_joints > 0 or bad_weights > 0 or bad_values > 0
    return bad


def skin_normals(rig: Rig, pose: Pose | None = None, normals=None) -> np.ndarray:
    """The unit normals of a rig's vertices in a pose.

    The blended linear part M's inverse transpose is applied (as ``|det M| M^-T``, the cofactor
    matrix times sign(det M): scale, non-uniform scale and mirroring are corrected), then the
    result is normalised.

    Parameters
    ----------
    rig : Rig
        The model.
    pose : Pose, optional
        A pose of its skeleton (default: the rest pose).
    normals : (n, 3) float64, optional
        Rest normals (default: the rig's "NORMAL" attribute).

    Returns
    -------
    (n, 3) float64

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> cgaskin.skin_normals(arm, arm.pose("wave", 1.0))[-1].round(3)   # the tip points up
    array([0., 1., 0.])
    """
    pose = rig.rest_pose() if pose is None else check_pose(rig, pose)
    normals = rig.attributes.get("NORMAL") if normals is None else normals
    if normals is None:
        raise InvalidInputError("the rig has no NORMAL attribute; pass normals (n, 3)")
    normals = float_array(normals, "normals", 3, ndim=2)
    affines = pose.bone_affines().reshape(-1, 3, 4)
    lin = np.einsum("nk,nkij->nij", rig.weights, affines[rig.joints][..., :3])
    cof = np.stack([np.cross(lin[:, 1], lin[:, 2]), np.cross(lin[:, 2], lin[:, 0]),
                    np.cross(lin[:, 0], lin[:, 1])], axis=1)       # rows of det(M) M^-T
    det = np.einsum("ni,ni->n", lin[:, 0], cof[:, 0])
    # the cofactor matrix is det(M) M^-T: a mirrored blend (det < 0) would turn the normals inside out
    out = np.einsum("nij,nj->ni", cof, normals) * np.where(det < 0, -1.0, 1.0)[:, None]
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return out / np.where(length > 0, length, 1.0)
