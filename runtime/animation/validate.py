"""Validation of skinned-mesh arrays at the boundary of the library.

Loaders, ``Rig`` constructors and the mesh operations call ``check_mesh`` once, so that every kernel
after it can assume clean data: finite float64 positions, int64 faces inside the vertex range, and
exactly four influences per vertex with non-negative weights that sum to 1 (to float64 rounding:
skinning must match glTF to 1e-9 of the model's size, and a row off 1 by e moves a vertex by e
times its distance from the origin).

Real files break the last rule routinely (float32 weights sum to 1 only within ~1e-7; assimp's
conversions store rows up to 1.8e-3 off; ``quad_skin.glb`` has 10 influences per vertex, and keeping
the largest 4 drops up to 0.37 of a row's weight), so those cases are repaired: float32 noise
silently, real defects with a warning. Everything else that is wrong is refused with an
``InvalidInputError`` that says which vertex holds which value.
"""
from __future__ import annotations


import numpy as np

from .._shared.warn import warn
from ..errors import InvalidInputError, ModelWarning
from ..tolerances import tol

MAX_INFLUENCES = 4
#: Rows whose sum is off 1 by more than this are reported (a warning) before being renormalised.
#: float32 files (every glTF) round each weight to ~6e-8 relative, so their rows sum to 1 only
#: within ~2.4e-7: that much is storage noise, renormalised silently.
WEIGHT_SUM_TOLERANCE = tol.weight_sum
#: Rows within this of 1 are left bit for bit as they are. One float64 division by the row sum
#: lands within ~8e-16 (4 roundings and 3 additions of 2^-53 each), so a second ``check_mesh`` never
#: changes a row again: the function is idempotent, which save -> load round trips rely on.
EXACT_SUM_TOLERANCE = tol.exact_weight_sum
#: dtype kinds of numpy's floating / integer types (bool, complex, strings and objects are neither)
_REAL, _INTEGER = "fiu", "iu"


def _prefix(source: str) -> str:
    return f"{source}: " if source else ""


def _as_array(value, name: str, source: str) -> np.ndarray:
    try:
        return np.array(value)  # always a copy: the caller's array is never modified
    except Exception as exc:  # ragged lists and the like
        raise InvalidInputError(f"{_prefix(source)}{name} is not an array: {exc}") from None


def _first_bad_row(mask: np.ndarray) -> int:
    """Index of the first True row of a (n,) or (n, k) boolean mask."""
    rows = mask if mask.ndim == 1 else mask.any(axis=1)
    return int(np.flatnonzero(rows)[0])


def _row_sums(weights: np.ndarray) -> np.ndarray:
    """(n,) sums of the rows, added left to right (as ``weights.sum(axis=1)`` does for a few columns,
    and several times faster on them): one summation order for both paths of ``check_mesh``."""
    columns = weights.T
    total = columns[0]
    for column in columns[1:]:
        total = total + column
    return total


def _clean_joints(joints, weights, n_bones):
    """``joints`` with unused slots set to bone 0 when the influences (float64 / int64, shapes
    checked) are otherwise already what ``check_mesh`` makes of them, so that it would return them
    unchanged; None sends them through the full check and its repairs. The cheap tests of a rig made
    from another rig's arrays (every cut and tear makes one), slot by slot: columns, not rows."""
    if weights.shape[1] != MAX_INFLUENCES or len(weights) == 0:
        return None
    if not (weights.min() >= 0.0 and np.isfinite(weights.sum())):       # (NaN fails the comparison)
        return None
    used = weights > 0
    slot = used.T
    # weighted slots first, so slot 0 weighted means no empty row
    if not slot[0].all() or (slot[2] > slot[1]).any() or (slot[3] > slot[2]).any():
        return None
    joints = np.where(used, joints, 0)
    if joints.min() < 0 or (n_bones is not None and joints.max() >= n_bones):
        return None
    bone = joints.T
    twice = (slot[1] & (bone[0] == bone[1])) | (slot[2] & ((bone[0] == bone[2]) | (bone[1] == bone[2]))) \
        | (slot[3] & ((bone[0] == bone[3]) | (bone[1] == bone[3]) | (bone[2] == bone[3])))
    if twice.any() or np.abs(_row_sums(weights) - 1.0).max() > EXACT_SUM_TOLERANCE:
        return None
    return joints


def warn_dropped_influences(source: str, n_vertices: int, most: int) -> None:
    """The one warning for vertices with more than 4 influences cut to their 4 largest (glTF
    files here, assimp's conversions in ``cgaskin.rigs.assimp``)."""
    warn(f"{_prefix(source)}{n_vertices} vertices have more than {MAX_INFLUENCES} bone influences (up "
         f"to {most}); kept the {MAX_INFLUENCES} largest weights of each and renormalised", ModelWarning)


def check_mesh(vertices, faces, joints, weights, *, n_bones: int | None = None, source: str = ""):
    """Validate and normalise a skinned triangle mesh; return new arrays.

    Parameters
    ----------
    vertices : (n, 3) real
        Rest positions; must be finite.
    faces : (m, 3) integer
        Vertex indices, each in ``[0, n)``.
    joints : (n, k) integer, k >= 1
        Bone index of each influence. Slots whose weight is 0 are ignored (their index may be
        anything); the others must lie in ``[0, n_bones)``.
    weights : (n, k) real, k >= 1
        Influence weights: finite and >= 0, at least one > 0 per vertex.
    n_bones : int, optional
        Number of bones; when given, joint indices of weighted slots must be below it.
    source : str
        Where the data come from (a file name), used in messages and warnings.

    Returns
    -------
    vertices : (n, 3) float64
    faces : (m, 3) int64
    joints : (n, 4) int64, unused slots hold bone 0
    weights : (n, 4) float64, each row sums to 1 within ``EXACT_SUM_TOLERANCE``

    Repairs (each with one ``UserWarning`` naming ``source``): slots that name the same bone twice
    are merged (exact: skinning is linear in the weights, so no warning); more than 4 influences
    keep the 4 largest; rows whose sum is off 1 by more than ``WEIGHT_SUM_TOLERANCE`` are divided by
    their sum. Rows off by less (float32 storage noise) are divided by their sum silently; rows
    within ``EXACT_SUM_TOLERANCE`` are left bit for bit alone, so data that went through
    ``check_mesh`` once pass it again unchanged (what makes save -> load round trips exact).
    Weighted slots are moved to the front of each row, keeping their order.

    Raises
    ------
    InvalidInputError
        Wrong shapes or dtypes, non-finite positions, faces out of range, NaN/inf or negative
        weights, a vertex without any weight, a joint index outside ``[0, n_bones)``.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> vertices, faces, joints, weights = cgaskin.check_mesh(
    ...     arm.vertices, arm.faces, arm.joints[:, :2], arm.weights[:, :2], n_bones=3)
    >>> joints.shape, weights.dtype                        # padded to four influences
    ((690, 4), dtype('float64'))
    """
    pre = _prefix(source)
    vertices = _as_array(vertices, "vertices", source)
    faces = _as_array(faces, "faces", source)
    joints = _as_array(joints, "joints", source)
    weights = _as_array(weights, "weights", source)

    # --- vertices ---------------------------------------------------------------------------
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidInputError(f"{pre}vertices must have shape (n, 3), got {vertices.shape}")
    if vertices.dtype.kind not in _REAL:
        raise InvalidInputError(f"{pre}vertices must be real numbers, got dtype {vertices.dtype}")
    vertices = vertices.astype(np.float64, copy=False)   # (a copy already: _as_array)
    n = len(vertices)
    # (a finite sum is the cheap proof that every value is; an overflowing one is checked value by value)
    bad = None if np.isfinite(vertices.sum()) else ~np.isfinite(vertices)
    if bad is not None and bad.any():
        v = _first_bad_row(bad)
        raise InvalidInputError(
            f"{pre}vertex {v} has a non-finite position {vertices[v].tolist()} "
            f"({int(bad.any(axis=1).sum())} such vertices); fix or remove them before skinning")

    # --- faces ------------------------------------------------------------------------------
    if faces.size == 0:
        faces = faces.reshape(0, 3)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidInputError(f"{pre}faces must have shape (m, 3) (triangles), got {faces.shape}")
    if faces.dtype.kind not in _INTEGER:
        raise InvalidInputError(f"{pre}faces must hold integer vertex indices, got dtype {faces.dtype}")
    faces = faces.astype(np.int64, copy=False)
    if faces.size and (faces.min() < 0 or faces.max() >= n):
        bad = (faces < 0) | (faces >= n)
        f = _first_bad_row(bad)
        raise InvalidInputError(
            f"{pre}face {f} = {faces[f].tolist()} refers to a vertex outside [0, {n}) "
            f"({int(bad.any(axis=1).sum())} such faces); faces must index the {n} vertices")

    # --- joints and weights: shapes and values ------------------------------------------------
    if weights.ndim != 2 or weights.shape[0] != n or weights.shape[1] < 1:
        raise InvalidInputError(f"{pre}weights must have shape ({n}, k) with k >= 1 (one row per vertex), "
                                f"got {weights.shape}")
    if joints.shape != weights.shape:
        raise InvalidInputError(f"{pre}joints must have the shape of weights {weights.shape}, got {joints.shape}")
    if weights.dtype.kind not in _REAL:
        raise InvalidInputError(f"{pre}weights must be real numbers, got dtype {weights.dtype}")
    if joints.dtype.kind not in _INTEGER:
        raise InvalidInputError(f"{pre}joints must hold integer bone indices, got dtype {joints.dtype}")
    weights = weights.astype(np.float64, copy=False)
    joints = joints.astype(np.int64, copy=False)
    clean = _clean_joints(joints, weights, n_bones)
    if clean is not None:
        return vertices, faces, clean, np.ascontiguousarray(weights)

    bad = ~np.isfinite(weights)
    if bad.any():
        v = _first_bad_row(bad)
        raise InvalidInputError(f"{pre}vertex {v} has non-finite weights {weights[v].tolist()} "
                                f"({int(bad.any(axis=1).sum())} such vertices)")
    bad = weights < 0
    if bad.any():
        v = _first_bad_row(bad)
        raise InvalidInputError(f"{pre}vertex {v} has negative weights {weights[v].tolist()} "
                                f"({int(bad.any(axis=1).sum())} such vertices); weights must be >= 0")
    used = weights > 0
    # Unused slots may hold any index (exporters write garbage there); give them bone 0 so that
    # no later lookup can go out of range.
    joints[~used] = 0
    bad = used & ((joints < 0) | ((joints >= n_bones) if n_bones is not None else False))
    if bad.any():
        v = _first_bad_row(bad)
        limit = f"[0, {n_bones})" if n_bones is not None else ">= 0"
        raise InvalidInputError(
            f"{pre}vertex {v} is weighted to bone indices {joints[v][used[v]].tolist()}, "
            f"which must be {limit} ({int(bad.any(axis=1).sum())} such vertices)")
    empty = ~used.any(axis=1)
    if empty.any():
        v = int(np.flatnonzero(empty)[0])
        raise InvalidInputError(
            f"{pre}vertex {v} has no weight at all ({int(empty.sum())} such vertices); every vertex "
            f"needs at least one bone with weight > 0 (bind unskinned vertices to a root bone)")

    # --- merge slots that name the same bone (exact: skinning is linear in the weights) -------
    k = weights.shape[1]
    for a in range(k):
        for b in range(a + 1, k):
            same = used[:, a] & used[:, b] & (joints[:, a] == joints[:, b])
            if same.any():
                weights[same, a] += weights[same, b]
                weights[same, b] = 0.0
                joints[same, b] = 0
                used[same, b] = False

    # --- at most 4 influences: keep the largest ----------------------------------------------
    counts = used.sum(axis=1)
    over = counts > MAX_INFLUENCES
    if over.any():
        rows = np.flatnonzero(over)
        # stable sort on -w: ties keep the file's slot order, so the result is deterministic
        order = np.argsort(-weights[rows], axis=1, kind="stable")
        drop = order[:, MAX_INFLUENCES:]
        weights[rows[:, None], drop] = 0.0
        joints[rows[:, None], drop] = 0
        used[rows[:, None], drop] = False
        warn_dropped_influences(source, len(rows), int(counts.max()))

    # --- compact the used slots to the front, keeping their order, then pad/trim to 4 ----------
    order = np.argsort(~used, axis=1, kind="stable")
    weights = np.take_along_axis(weights, order, axis=1)
    joints = np.take_along_axis(joints, order, axis=1)
    if k < MAX_INFLUENCES:
        pad = MAX_INFLUENCES - k
        weights = np.concatenate([weights, np.zeros((n, pad))], axis=1)
        joints = np.concatenate([joints, np.zeros((n, pad), dtype=np.int64)], axis=1)
    elif k > MAX_INFLUENCES:
        weights = np.ascontiguousarray(weights[:, :MAX_INFLUENCES])
        joints = np.ascontiguousarray(joints[:, :MAX_INFLUENCES])

    # --- rows must sum to 1 ----------------------------------------------------------------------
    sums = _row_sums(weights)
    deviation = np.abs(sums - 1.0)
    # over-4 rows were cut, so they are always renormalised (silently: warned above)
    off = (deviation > EXACT_SUM_TOLERANCE) | over
    if off.any():
        weights[off] /= sums[off, None]
        warned = deviation[~over] > WEIGHT_SUM_TOLERANCE
        if warned.any():
            worst = int(np.flatnonzero(~over)[np.argmax(np.where(warned, deviation[~over], -1.0))])
            warn(f"{pre}{int(warned.sum())} vertices have weights that do not sum to 1 (max deviation "
                 f"{deviation[worst]:.3g} at vertex {worst}); renormalised them", ModelWarning)
    return vertices, faces, joints, weights
