"""A splice's rows into an editing session's buffers and out again (undo): the part of ``Surgery``
(``session.py``) that writes what a stroke or a hole made (``session_write.write_splice``, one
kernel), keeps its BVH, bone influences and bounds with it, and takes it back exactly."""
from __future__ import annotations

import numpy as np

from .session_undo import Undo
from .session_write import SessionBuffers, _grown_box, write_splice

__all__ = ["SplicedRows"]

#: the per-vertex buffers a stroke writes, in ``session_write.SessionBuffers``' order
_VERTEX_ARRAYS = ("vertices", "labels", "joints", "weights", "boundary")


class SplicedRows:
    """What ``Surgery`` does with a splice's rows (a base class: it reads the session's buffers)."""

    def _edit_bvh(self, removed, inserted, near, moved, positions, faces, moved_rows, first_row, end_row) -> None:
        """``DynamicBVH.edit``, with the bone influences kept (once a posed stroke made them) and what is
        posed of the changed nodes and rows forgotten (``moved_rows`` and the rows from ``first_row`` to
        ``end_row``: their rest positions changed, or they are new or gone)."""
        if not self._influences.kept:
            self._bvh.edit(removed, inserted, near, moved, positions, faces)
            self._scratch.reset()
            return
        leaves, first_node = self._influences.removing(removed), self._bvh.n_nodes
        self._bvh.edit(removed, inserted, near, moved, positions, faces)
        changed = self._influences.edited(leaves, first_node, inserted, moved, self.joints, self.weights)
        if changed is None:
            self._scratch.reset()
        else:
            self._scratch.forget(changed, self._bvh.parents,
                                 np.concatenate((moved_rows, np.arange(first_row, end_row))))

    def _apply(self, splice) -> Undo:
        p, n, m, k = len(splice.rows), self.n_vertices, self._faces.n, len(splice.pieces)
        added = len(splice.vertices) - p
        buffers = [self._arrays[name] for name in _VERTEX_ARRAYS]
        # a stroke changes the labels (the far side) and positions (an opening) of a few of its patch's
        # rows; their weights and attributes stay: those are only appended
        written = write_splice(SessionBuffers(*[buffer.reserve(added) for buffer in buffers],
                                              self._faces.reserve(k), self._alive.reserve(k)), n, m, splice)
        for buffer in buffers:
            buffer.n += added
        self._faces.n += k
        self._alive.n += k
        for name, (buffer, _) in self._attributes.items():
            buffer.append(splice.attributes[name][p:])
        # (a new row's bones are some of its sources': the bones in use, ``_used``, stay as they are)
        scalars = (self.top_label, self._labelled, self._bounds.copy())
        self.top_label = max(self.top_label, written.top)
        # each piece into its face's leaf (it lies inside that face: no descent), then the faces out
        self._edit_bvh(splice.removed, np.arange(m, self._faces.n), splice.parents, written.moved_faces,
                       self.positions, self.faces, written.moved, n, self.n_vertices)
        self._grow_bounds(written.moved, n, written.old_positions)
        return Undo(n, m, written.rows, {"vertices": written.old_vertices, "labels": written.old_labels},
                    written.moved, splice.removed, splice.parents, splice.kept, written.old_kept, written.moved_faces,
                    splice.boundary_rows, written.old_flags, scalars)

    def _grow_bounds(self, moved, first_new, old) -> None:
        """The bounding box of the surface after the rows ``moved`` changed position (from ``old``) and
        rows from ``first_new`` on appeared: grown by their new positions, or found again from every
        vertex when a moved one was on the old box's side."""
        if len(old) and ((old == self._bounds[0]) | (old == self._bounds[1])).any():
            moved, first_new = np.empty(0, np.int64), 0
            box = np.stack([np.full(3, np.inf), np.full(3, -np.inf)])
        else:
            box = self._bounds.copy()
        if _grown_box(self.positions, moved, first_new, box):
            self._set_bounds(box)

    def _revert(self, record: Undo) -> None:
        rows, m, n = record.rows, self._faces.n, self.n_vertices
        self._faces.truncate(record.m)
        self._alive.truncate(record.m)
        self._faces.view[record.kept] = record.old_kept
        self._alive.view[record.removed] = True
        for name in ("vertices", "joints", "weights", "labels"):
            self._arrays[name].truncate(record.n)
        for name, values in record.old_rows.items():
            self._arrays[name].view[rows] = values
        for buffer, _ in self._attributes.values():
            buffer.truncate(record.n)
        flags = self._arrays["boundary"]
        flags.truncate(record.n)
        valid = record.boundary_rows < record.n
        flags.view[record.boundary_rows[valid]] = record.old_flags[valid]
        self.top_label, self._labelled, bounds = record.scalars
        self._set_bounds(bounds)
        # the whole buffers: the faces taken out (ids from record.m on, vertices from record.n on) keep
        # their rows there until the next stroke overwrites them, and the BVH reads them as it lets them go
        near = _piece_in_each(record.removed, record.piece_parents, record.m)     # (its leaf takes the face back)
        self._edit_bvh(np.arange(record.m, m), record.removed, near, record.moved_faces,
                       self._arrays["vertices"].data, self._faces.data, record.moved, record.n, n)


def _piece_in_each(removed, parents, first_piece: int) -> np.ndarray:
    """(r,) for each face of ``removed`` (r,) a piece made inside it (face id ``first_piece + i`` for the
    piece i whose ``parents[i]`` it is), -1 where none was."""
    out = np.full(len(removed), -1, np.int64)
    if not len(removed):
        return out
    order = np.argsort(removed)
    at = order[np.minimum(np.searchsorted(removed, parents, sorter=order), len(removed) - 1)]
    found = np.flatnonzero(removed[at] == parents)          # (a wall piece's parent, -1, is no face)
    out[at[found]] = first_piece + found
    return out
