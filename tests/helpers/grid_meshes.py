"""Axis-aligned, box-like test meshes (issue 13's degenerate planes): the closed surface of a set of unit
voxels, every face a half of a grid square, so that planes along the grid run through rows of vertices,
along edges, and contain whole faces. Plain numpy."""
from __future__ import annotations

import numpy as np

from cgaskin import Rig

from .cut_checks import chain_skeleton


def voxel_rig(filled) -> Rig:
    """The closed, outward-wound surface of the voxels ``filled`` (nx, ny, nz) bool (voxel (i, j, k) is
    the unit cube from (i, j, k)), one welded vertex per grid point, each exposed unit square split into
    two triangles. A skinned rig with one bone, NORMAL and TEXCOORD_0. (Voxels that touch only along an
    edge give non-manifold edges: use ``staircase``.)"""
    filled = np.asarray(filled, bool)
    pad = np.zeros(np.add(filled.shape, 2), bool)
    pad[1:-1, 1:-1, 1:-1] = filled
    ids: dict = {}
    faces = []
    for axis in range(3):
        e, u, v = (np.eye(3, dtype=np.int64)[(axis + k) % 3] for k in range(3))
        for cell in np.argwhere(pad):
            for s in (1, -1):
                if pad[tuple(cell + s * e)]:
                    continue
                base = cell - 1 + (e if s > 0 else 0)
                quad = [base, base + u, base + u + v, base + v]
                if s < 0:
                    quad = quad[::-1]
                a, b, c, d = (ids.setdefault(tuple(int(x) for x in p), len(ids)) for p in quad)
                faces += [[a, b, c], [a, c, d]]
    vertices = np.array(sorted(ids, key=ids.get), np.float64)
    faces = np.array(faces, np.int64)
    normals = np.zeros_like(vertices)
    corners = vertices[faces]
    np.add.at(normals, faces.reshape(-1), np.repeat(np.cross(corners[:, 1] - corners[:, 0],
                                                             corners[:, 2] - corners[:, 0]), 3, axis=0))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    n = len(vertices)
    return Rig(vertices=vertices, faces=faces, joints=np.zeros((n, 4), np.int64),
               weights=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)), skeleton=chain_skeleton(1, np.random.default_rng(0)),
               attributes={"NORMAL": normals, "TEXCOORD_0": vertices[:, :2] / max(1.0, vertices.max())},
               name="voxels")


def staircase(heights) -> Rig:
    """``voxel_rig`` of columns of the given heights (nx, ny) int >= 1, non-increasing along x and y (a
    staircase: manifold, with steps whose treads and risers lie in grid planes)."""
    heights = np.asarray(heights, np.int64)
    assert (heights >= 1).all() and (np.diff(heights, axis=0) <= 0).all() and (np.diff(heights, axis=1) <= 0).all()
    return voxel_rig(np.arange(heights.max())[None, None, :] < heights[:, :, None])


def face_areas(rig) -> np.ndarray:
    corners = np.asarray(rig.vertices, np.float64)[np.asarray(rig.faces)]
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)


def slivers(rig, relative=1e-12) -> int:
    """Zero-area faces: three corners on a line up to rounding (twice the area below ``relative`` times
    the square of the longest side: a shape measure, so that a tiny but well-shaped triangle -- a plane
    that passes 1e-6 from a corner cuts one off -- or a thin real one is not one)."""
    if len(rig.faces) == 0:
        return 0
    corners = np.asarray(rig.vertices, np.float64)[np.asarray(rig.faces)]
    longest = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    return int(np.count_nonzero(2 * face_areas(rig) <= relative * longest ** 2))
