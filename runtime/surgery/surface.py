"""What cut and tear take of a rig: its checked mesh arrays (cached per rig), its label-aware welded
topology, and the records of the surface a tear stroke walks on (built per stroke for its patch:
``tear/patch.py``)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._shared.cache import rig_cached
from .._shared.frozen import kernel_array
from .._shared.jit import F2, I1, I2, record
from ..animation.rig import Rig
from ..errors import InvalidInputError
from .bvh import TriangleBVH
from .topology import Topology, rig_topology, topology

#: per-vertex attribute that tells slit copies apart from seam copies (see the module docstring)
TEAR_LABEL = "_TEAR"


def box_diagonal(points) -> float:
    """The length of the diagonal of the bounding box of ``points`` (n, 3) (0 for none), column by
    column (numpy reduces an (n, 3) array over its first axis ~20x slower than its three columns)."""
    if not len(points):
        return 0.0
    return float(np.linalg.norm([points[:, k].max() - points[:, k].min() for k in range(3)]))


def _labels(rig) -> np.ndarray:
    """(n,) int64 tear labels of the rig's vertices (0 without the attribute): whole numbers, any sign."""
    values = rig.attributes.get(TEAR_LABEL)
    if values is None:
        return np.zeros(rig.n_vertices, np.int64)
    values = np.asarray(values, dtype=np.float64).reshape(rig.n_vertices, -1)[:, 0]
    if not np.isfinite(values).all():
        raise InvalidInputError(f"attribute {TEAR_LABEL} holds non-finite values")
    labels = np.rint(values)
    bad = np.flatnonzero((labels != values) | (np.abs(labels) >= 2.0 ** 53))
    if len(bad):
        raise InvalidInputError(f"attribute {TEAR_LABEL} must hold whole numbers (labels of slit sides), "
                                f"got {float(values[bad[0]])!r} at vertex {bad[0]}")
    return labels.astype(np.int64)


def _build_tear_topology(rig) -> Topology:
    labels = _labels(rig)
    if not labels.any():
        return rig_topology(rig)
    return topology(kernel_array(rig.vertices), kernel_array(rig.faces), labels)


def tear_topology(rig) -> Topology:
    """The welded topology that ``tear`` walks on: vertices are one when their positions and their
    ``TEAR_LABEL`` values are equal (so seams weld and earlier slits stay open). Cached per rig."""
    return rig_cached(rig, "tear.topology", _build_tear_topology)


class WeldedMesh(NamedTuple):
    """The welded surface as the tear's kernels take it.

    positions : (w, 3) float64 welded vertices (their representatives' positions)
    faces : (m, 3) int64 welded corners of each face ; face_edges : (m, 3) int64 edge k of face f
    runs from corner k to corner k + 1 ; edges : (e, 2) int64 welded ends of each edge
    ef_offsets, ef_faces : CSR edge -> faces ; vf_offsets, vf_faces : CSR welded vertex -> faces
    """

    positions: np.ndarray
    faces: np.ndarray
    face_edges: np.ndarray
    edges: np.ndarray
    ef_offsets: np.ndarray
    ef_faces: np.ndarray
    vf_offsets: np.ndarray
    vf_faces: np.ndarray


#: the numba type of ``WeldedMesh`` (for precompile signatures)
WELDED_MESH = record(F2, I2, I2, I2, I1, I1, I1, I1)


@dataclass(frozen=True, eq=False)
class _Surface:
    """What one stroke needs of a rig in one pose (rest when posed is None).

    positions : (n, 3) float64 surface positions of every vertex (skinned when posed)
    faces : (m, 3) int64 the rig's faces (``mesh_arrays``)
    vertex_welded : (n,) int64 the welded vertex of each vertex (by position and tear label, as
        ``tear_topology`` welds)
    welded : WeldedMesh
    bvh : TriangleBVH over ``positions``
    boundary : (b,) int64 welded vertices on a boundary edge (borders, earlier slits)
    diagonal : float, bounding-box diagonal of ``positions``
    affines : (B, 12) bone maps of the pose, or None at rest
    """

    positions: np.ndarray
    faces: np.ndarray
    vertex_welded: np.ndarray
    welded: WeldedMesh
    bvh: TriangleBVH
    boundary: np.ndarray
    diagonal: float
    affines: np.ndarray | None


class MeshArrays(NamedTuple):
    """A rig's mesh as the surgery kernels take it: C-contiguous, float64/int64, 4 influences.

    vertices : (n, 3) float64 ; faces : (m, 3) int64 ; joints : (n, 4) int64 ; weights : (n, 4) float64
    """

    vertices: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray


def _checked_mesh(rig) -> MeshArrays:
    # (the kernels only read them: the writeable buffers behind the rig's read-only arrays, one type)
    vertices, faces, joints, weights = (kernel_array(a) for a in (rig.vertices, rig.faces, rig.joints, rig.weights))
    n = len(vertices)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or vertices.dtype.kind not in "fiu":
        raise InvalidInputError(f"rig.vertices must be a real (n, 3) array, got shape {vertices.shape} "
                                f"{vertices.dtype}")
    if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and faces.dtype.kind not in "iu"):
        raise InvalidInputError(f"rig.faces must be an (m, 3) integer array, got {faces.shape} {faces.dtype}")
    if len(faces) == 0:
        raise InvalidInputError("the rig has no faces: there is nothing to cut or tear")
    if faces.min() < 0 or faces.max() >= n:
        raise InvalidInputError(f"rig.faces must index the {n} vertices, got indices from {faces.min()} to "
                                f"{faces.max()}")
    if not np.isfinite(vertices).all():
        row = int(np.argwhere(~np.isfinite(vertices))[0, 0])
        raise InvalidInputError(f"rig.vertices hold a non-finite value (NaN or inf) in row {row}: "
                                f"{vertices[row].tolist()}")
    if joints.ndim != 2 or joints.shape != weights.shape or len(joints) != n or not 1 <= joints.shape[1] <= 4:
        raise InvalidInputError(f"rig.joints {joints.shape} and rig.weights {weights.shape} must both "
                                f"have shape ({n}, k) with k <= 4")
    if joints.dtype.kind not in "iu":
        raise InvalidInputError(f"rig.joints must hold integers, got {joints.dtype}")
    if not np.isfinite(weights).all() or (weights < 0).any():
        raise InvalidInputError("rig.weights must be finite and >= 0")
    n_bones = rig.skeleton.n_bones
    if joints.size and (joints.min() < 0 or joints.max() >= n_bones):
        raise InvalidInputError(f"rig.joints must index the {n_bones} bones, got indices from "
                                f"{joints.min()} to {joints.max()}")
    for name, values in rig.attributes.items():
        if len(np.asarray(values)) != n:
            raise InvalidInputError(f"attribute {name!r} has {len(values)} rows for {n} vertices")
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    joints = np.ascontiguousarray(joints, dtype=np.int64)
    weights = np.ascontiguousarray(weights, dtype=np.float64)
    if joints.shape[1] < 4:                      # pad to 4 influences (zero weights change nothing)
        pad = 4 - joints.shape[1]
        joints = np.concatenate([joints, np.zeros((n, pad), np.int64)], axis=1)
        weights = np.concatenate([weights, np.zeros((n, pad))], axis=1)
    return MeshArrays(vertices, faces, joints, weights)


def mesh_arrays(rig) -> MeshArrays:
    """The rig's mesh checked once (cut and tear check their input the same way) and converted for
    the kernels (no copy where the rig's arrays already are so); cached per rig.

    Raises InvalidInputError naming what is wrong: not a Rig, shapes, dtypes, non-finite values,
    negative weights, face or joint indices out of range, attribute row counts.
    """
    if not isinstance(rig, Rig):
        raise InvalidInputError(f"rig must be a cgaskin.Rig, got {type(rig).__name__}")
    return rig_cached(rig, "surgery.mesh", _checked_mesh)
