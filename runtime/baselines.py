"""Plain-numpy reference implementations, independent of the CGA kernels and of the runtime's own
transform helpers.

These functions are the oracles the tests compare cgaskin against, and the baselines the benchmarks
time. They use nothing of ``cgaskin`` but its error types, and no formula of its production code: the
quaternion/matrix conversions here are the Rodrigues form and Bar-Itzhack's eigenvector method where
``cgaskin.algebra.transforms`` writes out the matrix entries and uses Shepperd's method, and ``trs_matrix``
multiplies T @ R @ S where the runtime fills the blocks. So a bug cannot hide in both sides of a
comparison, and tests/algebra/test_transforms.py checks that the two implementations agree.

Conventions:

* quaternions are ``(x, y, z, w)`` (glTF order), unit length;
* matrices act on column vectors: ``p' = M @ [p, 1]``;
* ``bone_matrices`` are *skinning* matrices, i.e. already ``G[joint] @ inverse_bind`` (glTF semantics).
"""
from __future__ import annotations

import numpy as np

from .errors import InvalidInputError

__all__ = [
    "lbs_matrices", "dqs", "trs_matrix", "quat_to_matrix", "matrix_to_quat", "quat_multiply", "global_matrices",
]


# --------------------------------------------------------------------------------------------------
# Quaternions and matrices


def quat_multiply(a, b):
    """Hamilton product ``a * b`` of quaternions.

    a, b : (..., 4) float64 (x, y, z, w), broadcast against each other
    returns (..., 4) float64
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ], axis=-1)


def _cross_matrix(v):
    """(..., 3, 3) matrices [v]x with [v]x @ p = v x p, for v (..., 3)."""
    x, y, z = np.moveaxis(v, -1, 0)
    zero = np.zeros_like(x)
    return np.stack([np.stack([zero, -z, y], axis=-1),
                     np.stack([z, zero, -x], axis=-1),
                     np.stack([-y, x, zero], axis=-1)], axis=-2)


def quat_to_matrix(q):
    """Rotation matrix of a quaternion, in the Rodrigues form ``R = I + 2 w [v]x + 2 [v]x²``.

    For a unit quaternion (v, w) this is the rotation by 2 acos(w) about v (Euler-Rodrigues).

    q : (..., 4) float64 (x, y, z, w); normalised here, so any non-zero quaternion is accepted
    returns (..., 3, 3) float64
    """
    q = np.asarray(q, dtype=np.float64)
    if q.shape[-1:] != (4,):
        raise InvalidInputError(f"quat_to_matrix: expected (..., 4), got {q.shape}")
    norm = np.sqrt(np.sum(q * q, axis=-1, keepdims=True))
    if np.any(norm == 0) or not np.all(np.isfinite(norm)):
        raise InvalidInputError("quat_to_matrix: quaternions must be finite and non-zero")
    unit = q / norm
    k = _cross_matrix(unit[..., :3])
    w = unit[..., 3, None, None]
    return np.eye(3) + 2.0 * w * k + 2.0 * (k @ k)


def matrix_to_quat(m):
    """Unit quaternion of a rotation matrix, as the eigenvector of Bar-Itzhack's symmetric 4x4 matrix.

    For R = R(q), the matrix K below has the eigenvalue 1 with eigenvector q = (x, y, z, w) and the
    triple eigenvalue -1/3 (Bar-Itzhack 2000, "New method for extracting the quaternion from a
    rotation matrix"): the gap of 4/3 keeps the eigenvector accurate for every angle, 180° included.

    m : (..., 3, 3) or (..., 4, 4) float64; only the upper-left 3x3 block is read and it must be a
        rotation (orthonormal, det +1)
    returns (..., 4) float64 (x, y, z, w), unit length, sign chosen with w >= 0 (for exact 180°
        rotations, w == 0 and the overall sign is the eigensolver's)
    """
    m = np.asarray(m, dtype=np.float64)
    if m.ndim < 2 or m.shape[-2:] not in ((3, 3), (4, 4)):
        raise InvalidInputError(f"matrix_to_quat: expected (..., 3, 3) or (..., 4, 4), got {m.shape}")
    r = m[..., :3, :3]
    if not np.all(np.isfinite(r)):
        raise InvalidInputError("matrix_to_quat: matrices must be finite")
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = (np.moveaxis(r[..., i, :], -1, 0) for i in range(3))
    k = np.stack([
        np.stack([r00 - r11 - r22, r10 + r01, r20 + r02, r21 - r12], axis=-1),
        np.stack([r10 + r01, r11 - r00 - r22, r21 + r12, r02 - r20], axis=-1),
        np.stack([r20 + r02, r21 + r12, r22 - r00 - r11, r10 - r01], axis=-1),
        np.stack([r21 - r12, r02 - r20, r10 - r01, r00 + r11 + r22], axis=-1),
    ], axis=-2) / 3.0
    _, vectors = np.linalg.eigh(k)                  # eigenvalues in ascending order
    q = vectors[..., :, -1]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:4] < 0, -q, q)


def trs_matrix(t, q, s):
    """Affine matrix ``T @ R @ S`` (glTF node transform order), as the product of the three.

    t : (..., 3) float64 translation
    q : (..., 4) float64 rotation quaternion (x, y, z, w)
    s : (..., 3) float64 per-axis scale
    returns (..., 4, 4) float64, leading dimensions broadcast
    """
    t = np.asarray(t, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    s = np.asarray(s, dtype=np.float64)
    lead = np.broadcast_shapes(t.shape[:-1], q.shape[:-1], s.shape[:-1])
    translate, rotate, scale = (np.tile(np.eye(4), lead + (1, 1)) for _ in range(3))
    translate[..., :3, 3] = t
    rotate[..., :3, :3] = quat_to_matrix(q)
    for axis in range(3):
        scale[..., axis, axis] = s[..., axis]
    return translate @ rotate @ scale


def global_matrices(parents, local):
    """Global transforms along a node hierarchy.

    parents : (j,) int, parent index or -1 for roots, in topological order (parents[i] < i)
    local : (j, 4, 4) float64 transform of each node relative to its parent
    returns (j, 4, 4) float64, ``G[i] = G[parents[i]] @ local[i]``
    """
    parents = np.asarray(parents, dtype=np.int64)
    local = np.asarray(local, dtype=np.float64)
    if local.shape != (len(parents), 4, 4):
        raise InvalidInputError(f"global_matrices: local must be ({len(parents)}, 4, 4), got {local.shape}")
    out = np.empty_like(local)
    for i, p in enumerate(parents):
        if p >= i:
            raise InvalidInputError(f"global_matrices: parents must be topologically sorted "
                                    f"(node {i} has parent {p})")
        out[i] = local[i] if p < 0 else out[p] @ local[i]
    return out


# --------------------------------------------------------------------------------------------------
# Skinning


def _check_skin_inputs(vertices, joints, weights, bone_matrices):
    vertices = np.asarray(vertices, dtype=np.float64)
    joints = np.asarray(joints)
    weights = np.asarray(weights, dtype=np.float64)
    bone_matrices = np.asarray(bone_matrices, dtype=np.float64)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidInputError(f"vertices must be (n, 3), got {vertices.shape}")
    if joints.shape != weights.shape or joints.ndim != 2 or len(joints) != len(vertices):
        raise InvalidInputError(f"joints {joints.shape} and weights {weights.shape} must both be "
                                f"(n, k) with n = {len(vertices)}")
    if bone_matrices.ndim != 3 or bone_matrices.shape[1:] != (4, 4):
        raise InvalidInputError(f"bone_matrices must be (b, 4, 4), got {bone_matrices.shape}")
    if joints.size and (joints.min() < 0 or joints.max() >= len(bone_matrices)):
        raise InvalidInputError(f"joint indices must lie in [0, {len(bone_matrices)})")
    return vertices, joints.astype(np.int64), weights, bone_matrices


#: Vertices per block in ``lbs_matrices``: bounds the gathered (block, k, 12) array to ~25 MB at k = 4.
_LBS_BLOCK = 1 << 16


def lbs_matrices(vertices, joints, weights, bone_matrices):
    """Matrix linear blend skinning: ``p' = (Σ_k w_k M[j_k]) @ [p, 1]``.

    The 3x4 affine rows of the influences are blended first (one einsum over the gathered bones),
    then applied once per vertex; processed in blocks so that memory stays bounded for any n.

    vertices : (n, 3) float64 bind-pose positions
    joints : (n, k) int bone indices
    weights : (n, k) float64 (used as given: not renormalised)
    bone_matrices : (b, 4, 4) float64 skinning matrices ``G @ inverse_bind``
    returns (n, 3) float64
    """
    vertices, joints, weights, bone_matrices = _check_skin_inputs(vertices, joints, weights, bone_matrices)
    rows = np.ascontiguousarray(bone_matrices[:, :3, :].reshape(-1, 12))
    out = np.empty_like(vertices)
    for start in range(0, len(vertices), _LBS_BLOCK):
        block = slice(start, start + _LBS_BLOCK)
        a = np.einsum("nk,nkc->nc", weights[block], rows[joints[block]]).reshape(-1, 3, 4)
        v = vertices[block]
        out[block] = a[:, :, 0] * v[:, 0:1] + a[:, :, 1] * v[:, 1:2] + a[:, :, 2] * v[:, 2:3] + a[:, :, 3]
    return out


def _rigid_and_stretch(bone_matrices):
    """Split each ``[A | t]`` into a rigid part and a stretch: ``A = R @ S`` (polar decomposition).

    returns (R (b, 3, 3), S (b, 3, 3) symmetric positive definite, t (b, 3))
    """
    a = bone_matrices[:, :3, :3]
    u, sigma, vt = np.linalg.svd(a)
    if np.any(np.linalg.det(a) <= 0) or np.any(sigma[:, -1] <= 1e-12 * sigma[:, 0]):
        raise InvalidInputError("dqs: bone matrices must be invertible and keep orientation (det > 0); "
                                "dual quaternions cannot represent reflections")
    rot = u @ vt
    stretch = np.einsum("bji,bj,bjk->bik", vt, sigma, vt)   # V diag(σ) Vᵀ
    return rot, stretch, bone_matrices[:, :3, 3]


def dqs(vertices, joints, weights, bone_matrices):
    """Dual-quaternion skinning (Kavan et al. 2008, "Geometric skinning with approximate dual
    quaternion blending"), including its two-phase treatment of scale.

    Each skinning matrix ``[A | t]`` is split as ``A = R @ S`` with R a rotation and S the symmetric
    stretch (polar decomposition; for a uniform scale s, ``R = A / s`` and ``S = s I``). Following the
    paper's section on non-rigid transformations, a vertex is first deformed by the linear blend of
    the stretches, ``p₁ = Σ w_k S_k p``, and then by the normalised blend of the unit dual quaternions
    of the rigid parts ``(R_k, t_k)``. The blend flips each dual quaternion into the hemisphere of the
    vertex's first influence (antipodality), so that it takes the short way round. With a single
    influence, or with bones that only translate, the result equals matrix LBS exactly.

    vertices : (n, 3) float64 bind-pose positions
    joints : (n, k) int bone indices
    weights : (n, k) float64
    bone_matrices : (b, 4, 4) float64 skinning matrices ``G @ inverse_bind``, det > 0
    returns (n, 3) float64
    """
    vertices, joints, weights, bone_matrices = _check_skin_inputs(vertices, joints, weights, bone_matrices)
    rot, stretch, trans = _rigid_and_stretch(bone_matrices)
    # Unit dual quaternion per bone: real part q, dual part ½ (t, 0) q.
    real = matrix_to_quat(rot)
    dual = 0.5 * quat_multiply(np.concatenate([trans, np.zeros((len(trans), 1))], axis=1), real)

    first = real[joints[:, 0]]
    blend_real = np.zeros((len(vertices), 4))
    blend_dual = np.zeros((len(vertices), 4))
    blend_stretch = np.zeros((len(vertices), 3, 3))
    for k in range(joints.shape[1]):
        j = joints[:, k]
        sign = np.where(np.einsum("ni,ni->n", real[j], first) < 0, -1.0, 1.0)
        w = weights[:, k] * sign
        blend_real += w[:, None] * real[j]
        blend_dual += w[:, None] * dual[j]
        blend_stretch += weights[:, k, None, None] * stretch[j]

    norm = np.linalg.norm(blend_real, axis=1, keepdims=True)
    if np.any(norm == 0):
        raise InvalidInputError("dqs: a vertex has all-zero weights")
    c0 = blend_real / norm
    ce = blend_dual / norm
    p = np.einsum("nij,nj->ni", blend_stretch, vertices)
    # Kavan's formula for applying a (not necessarily exactly unit) normalised dual quaternion: the
    # rotation by c0, plus the translation 2 (w0 dε - wε d0 + d0 × dε); it is correct even though the
    # blended dual part is not orthogonal to the real part.
    v0, w0 = c0[:, :3], c0[:, 3:]
    ve, we = ce[:, :3], ce[:, 3:]
    rotated = p + 2 * np.cross(v0, np.cross(v0, p) + w0 * p)
    return rotated + 2 * (w0 * ve - we * v0 + np.cross(v0, ve))
