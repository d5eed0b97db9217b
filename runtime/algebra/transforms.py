"""Quaternions, rotation matrices and glTF node transforms (T @ R @ S) in plain numpy.

Conventions: quaternions are ``(x, y, z, w)`` (glTF order); matrices act on column vectors,
``p' = M @ [p, 1]``.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError

__all__ = ["quat_to_matrix", "matrix_to_quat", "trs_matrix", "matrix_to_trs"]


def quat_to_matrix(q):
    """Rotation matrix of a quaternion.

    q : (..., 4) float64 (x, y, z, w); normalised here, so any non-zero quaternion is accepted
    returns (..., 3, 3) float64
    """
    q = np.asarray(q, dtype=np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(norm == 0) or not np.all(np.isfinite(norm)):
        raise InvalidInputError("quat_to_matrix: quaternions must be finite and non-zero")
    x, y, z, w = np.moveaxis(q / norm, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=-2)


def matrix_to_quat(m):
    """Unit quaternion of a rotation matrix (Shepperd's method).

    Shepperd picks, per matrix, the largest of ``4w², 4x², 4y², 4z²`` (read off the trace and the
    diagonal) to divide by, so the result stays accurate at and near 180° rotations, where the
    textbook ``w = sqrt(1 + trace) / 2`` formula divides by ~0.

    m : (..., 3, 3) or (..., 4, 4) float64; only the upper-left 3x3 block is read and it must be a
        rotation (orthonormal, det +1); no scale is removed
    returns (..., 4) float64 (x, y, z, w), unit length, sign chosen with w >= 0 (for exact 180°
        rotations, w == 0 and the sign of the first non-zero component is as Shepperd gives it)
    """
    m = np.asarray(m, dtype=np.float64)
    if m.shape[-2:] not in ((3, 3), (4, 4)):
        raise InvalidInputError(f"matrix_to_quat: expected (..., 3, 3) or (..., 4, 4), got {m.shape}")
    r = m[..., :3, :3]
    m00, m11, m22 = r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]
    trace = m00 + m11 + m22
    # 4 * (w², x², y², z²), up to the rounding of r; the largest is >= 1, a safe divisor.
    candidates = np.stack([1 + trace, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22],
                          axis=-1)
    choice = np.argmax(candidates, axis=-1)
    q = np.empty(r.shape[:-2] + (4,))
    # Each branch: one component from the diagonal, the other three from sums and differences of
    # the off-diagonal pairs, all divided by 4 times the large component.
    s = np.sqrt(np.maximum(np.take_along_axis(candidates, choice[..., None], -1)[..., 0], 0.0)) * 2
    d21, d02, d10 = r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]
    s21, s02, s10 = r[..., 2, 1] + r[..., 1, 2], r[..., 0, 2] + r[..., 2, 0], r[..., 1, 0] + r[..., 0, 1]
    branches = [
        (d21 / s, d02 / s, d10 / s, s / 4),   # w largest
        (s / 4, s10 / s, s02 / s, d21 / s),   # x largest
        (s10 / s, s / 4, s21 / s, d02 / s),   # y largest
        (s02 / s, s21 / s, s / 4, d10 / s),   # z largest
    ]
    with np.errstate(divide="ignore", invalid="ignore"):
        for k, branch in enumerate(branches):
            sel = choice == k
            if np.any(sel):
                q[sel] = np.stack([np.broadcast_to(c, choice.shape)[sel] for c in branch], axis=-1)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:4] < 0, -q, q)


def trs_matrix(t, q, s):
    """Affine matrix ``T @ R @ S`` (glTF node transform order).

    t : (..., 3) float64 translation
    q : (..., 4) float64 rotation quaternion (x, y, z, w)
    s : (..., 3) float64 per-axis scale
    returns (..., 4, 4) float64, leading dimensions broadcast
    """
    t = np.asarray(t, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    s = np.asarray(s, dtype=np.float64)
    lead = np.broadcast_shapes(t.shape[:-1], q.shape[:-1], s.shape[:-1])
    out = np.zeros(lead + (4, 4))
    # R @ diag(s) scales the columns of R.
    out[..., :3, :3] = quat_to_matrix(q) * s[..., None, :]
    out[..., :3, 3] = t
    out[..., 3, 3] = 1.0
    return out


def matrix_to_trs(m):
    """Decompose an affine 4x4 matrix into translation, rotation and per-axis scale.

    The rotation is the orthogonal factor of the polar decomposition of the 3x3 block (the nearest
    rotation, exact for T @ R @ S matrices); scales are the column norms, with the x scale negated
    when the block is a reflection (det < 0). Shear cannot be represented: the result is the
    nearest TRS, which is why ``Skeleton.rest_matrices`` keeps the exact matrix.

    m : (4, 4) float
    returns : translation (3,) float64, rotation (4,) float64 (x, y, z, w), scale (3,) float64
    """
    m = np.asarray(m, dtype=np.float64)
    a = m[:3, :3].copy()
    scale = np.linalg.norm(a, axis=0)
    if np.linalg.det(a) < 0:
        scale[0] = -scale[0]
        a[:, 0] = -a[:, 0]
    u, _, vt = np.linalg.svd(a)
    r = u @ vt
    if np.linalg.det(r) < 0:  # only for singular blocks (a zero scale): pick the proper rotation
        u[:, -1] = -u[:, -1]
        r = u @ vt
    return m[:3, 3].copy(), matrix_to_quat(r), scale
