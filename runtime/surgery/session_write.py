"""A stroke's splice written into an editing session's buffers, in one kernel (``session.py``): two
dozen numpy operations on a few hundred rows cost a small stroke a fifth of its time; and the
surface's bounding box grown by the rows it wrote."""
from typing import NamedTuple

import numpy as np

from .._shared.jit import B1, F2, I1, I2, i8, kernel, record

__all__ = ["SessionBuffers", "SpliceRows", "Written", "write_splice"]


class SessionBuffers(NamedTuple):
    """A session's buffers, with room for the rows a splice appends: vertices (N, 3), labels (N,),
    joints (N, 4), weights (N, 4), flags (N,) boundary flags ; faces (M, 3), alive (M,)."""

    vertices: np.ndarray
    labels: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    flags: np.ndarray
    faces: np.ndarray
    alive: np.ndarray


class SpliceRows(NamedTuple):
    """A splice's rows as the kernel writes them (``tear/splice.Splice``, ``session_drill.DrillSplice``):
    patch_rows (p,) the source vertices of its first p rows, of which it may change those at ``changed``
    (c,) (increasing) ; vertices (p + v, 3), labels, joints, weights : its rows ; boundary_rows (b,),
    boundary_flags (b,) ; removed (a,), kept (r,) with kept_corners (r, 3), pieces (k, 3) : its faces."""

    patch_rows: np.ndarray
    changed: np.ndarray
    vertices: np.ndarray
    labels: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    boundary_rows: np.ndarray
    boundary_flags: np.ndarray
    removed: np.ndarray
    kept: np.ndarray
    kept_corners: np.ndarray
    pieces: np.ndarray


class Written(NamedTuple):
    """What undo needs of a written splice: rows (c,) = patch_rows[changed], their old_vertices (c, 3)
    and old_labels (c,), moved (u,) the rows whose position changed (increasing) and their
    old_positions (u, 3), old_flags (b,), old_kept (r, 3), moved_faces (the kept faces with a moved
    corner), top (the highest label written)."""

    rows: np.ndarray
    old_vertices: np.ndarray
    old_labels: np.ndarray
    moved: np.ndarray
    old_positions: np.ndarray
    old_flags: np.ndarray
    old_kept: np.ndarray
    moved_faces: np.ndarray
    top: int


def write_splice(buffers: SessionBuffers, n: int, m: int, splice) -> Written:
    """Write ``splice`` (any record with ``SpliceRows``' fields but ``patch_rows``, which it calls
    ``rows``) into ``buffers``, which hold n vertices and m face rows; what undo needs."""
    rows = SpliceRows(splice.rows, splice.changed, splice.vertices, splice.labels, splice.joints, splice.weights,
                      splice.boundary_rows, splice.boundary_flags, splice.removed, splice.kept, splice.kept_corners,
                      splice.pieces)
    return Written(*_write_splice(tuple(buffers), n, m, tuple(rows)))


@kernel((record(F2, I1, I2, F2, B1, I2, B1), i8, i8, record(I1, I1, F2, I1, I2, F2, I1, B1, I1, I1, I2, I2)),
        cost=1.8)
def _write_splice(buffers, n, m, splice):
    """``write_splice``: ``buffers`` a ``SessionBuffers`` and ``splice`` a ``SpliceRows``, as tuples;
    returns ``Written``'s fields."""
    vertices, labels, joints, weights, flags, faces, alive = buffers
    (patch_rows, changed, new_vertices, new_labels, new_joints, new_weights, boundary_rows, boundary_flags,
     removed, kept, kept_corners, pieces) = splice
    c, p = changed.shape[0], patch_rows.shape[0]
    rows = np.empty(c, np.int64)
    old_vertices, old_labels = np.empty((c, 3)), np.empty(c, np.int64)
    is_moved = np.zeros(c, np.bool_)
    for i in range(c):
        r, j = patch_rows[changed[i]], changed[i]
        rows[i] = r
        for k in range(3):
            old_vertices[i, k] = vertices[r, k]
            is_moved[i] = is_moved[i] or new_vertices[j, k] != vertices[r, k]
            vertices[r, k] = new_vertices[j, k]
        old_labels[i], labels[r] = labels[r], new_labels[j]
    moved, old_moved = rows[is_moved], old_vertices[is_moved]
    top = 0
    for j in range(new_labels.shape[0]):
        top = max(top, new_labels[j])
    for i in range(new_vertices.shape[0] - p):
        for k in range(3):
            vertices[n + i, k] = new_vertices[p + i, k]
        for k in range(4):
            joints[n + i, k], weights[n + i, k] = new_joints[p + i, k], new_weights[p + i, k]
        labels[n + i], flags[n + i] = new_labels[p + i], False
    old_flags = np.empty(boundary_rows.shape[0], np.bool_)
    for i in range(boundary_rows.shape[0]):
        old_flags[i], flags[boundary_rows[i]] = flags[boundary_rows[i]], boundary_flags[i]
    # faces: tombstones, the far side's new corners, the pieces appended
    old_kept = np.empty_like(kept_corners)
    n_moved_faces = 0
    moved_faces = np.empty(kept.shape[0], np.int64)
    for i in range(kept.shape[0]):
        touches = False
        for k in range(3):
            old_kept[i, k], faces[kept[i], k] = faces[kept[i], k], kept_corners[i, k]
            at = np.searchsorted(moved, kept_corners[i, k])
            touches = touches or (at < moved.shape[0] and moved[at] == kept_corners[i, k])
        if touches:                 # (an opening moves vertices: the faces at them move too)
            moved_faces[n_moved_faces] = kept[i]
            n_moved_faces += 1
    for f in removed:
        alive[f] = False
    for i in range(pieces.shape[0]):
        for k in range(3):
            faces[m + i, k] = pieces[i, k]
        alive[m + i] = True
    return (rows, old_vertices, old_labels, moved, old_moved, old_flags, old_kept, moved_faces[:n_moved_faces].copy(),
            top)


@kernel((F2, I1, i8, F2), cost=0.1)
def _grown_box(positions, moved, first_new, box):
    """Grow ``box`` (2, 3) in place by the positions of the rows ``moved`` and of every row from
    ``first_new`` on; whether it changed (numpy's reductions along the first axis of an (r, 3) array
    cost tens of microseconds)."""
    changed = False
    for i in range(moved.shape[0] + positions.shape[0] - first_new):
        r = moved[i] if i < moved.shape[0] else first_new + i - moved.shape[0]
        for k in range(3):
            x = positions[r, k]
            if x < box[0, k]:
                box[0, k], changed = x, True
            if x > box[1, k]:
                box[1, k], changed = x, True
    return changed
