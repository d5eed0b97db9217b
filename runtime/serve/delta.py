"""What changed in a session's mesh since a page last heard of it: the delta ``cgaskin serve`` sends
after each operation, so that the page writes a few rows of its buffers instead of loading the model
again.

A ``Mirror`` is the server's record of what one page holds: the rig it last sent (``Surgery.rig`` is
an immutable snapshot, so keeping it costs nothing) and, for faces and rim edges, which row sits in
which *slot* of the page's index buffers. Vertices keep their rows (a tear appends rows and rewrites
a few: the far side's labels, an opening's positions), so rows are compared in place. Faces do not
keep their place in ``rig.faces`` (removed faces close up the array), so they are matched as a
multiset of corner triples: a face that is still there keeps its slot, a new one takes a freed slot
or a new one at the end, and a freed slot that nothing takes is written as the degenerate (0, 0, 0),
which draws nothing and no ray hits.

Arrays travel as base64 of little-endian typed arrays (``encode``): rows and slots uint32, positions,
weights and other attributes float32 (what the page's buffers hold), joints uint16.
"""
from __future__ import annotations

import base64

import numpy as np

from ..view.model import rim_edges

#: the rig's vertex attributes a page holds (glTF name -> three.js attribute name, as GLTFLoader names them)
PAGE_ATTRIBUTES = {"NORMAL": "normal", "TANGENT": "tangent", "TEXCOORD_0": "uv", "TEXCOORD_1": "uv1",
                   "COLOR_0": "color"}


def encode(array, dtype) -> str:
    """Base64 of ``array`` as a C-ordered little-endian ``dtype`` array (the page reads it with a typed array)."""
    return base64.b64encode(np.ascontiguousarray(array, dtype=np.dtype(dtype).newbyteorder("<")).tobytes()).decode("ascii")


def _occurrences(ids: np.ndarray) -> np.ndarray:
    """(k,) int64: for each entry, how many equal entries come before it (0 for the first of its value),
    so that (id, occurrence) pairs are unique and a multiset compares as a set."""
    order = np.argsort(ids, kind="stable")
    ordered = ids[order]
    starts = np.flatnonzero(np.r_[True, ordered[1:] != ordered[:-1]])
    lengths = np.diff(np.r_[starts, len(ids)])
    rank = np.empty(len(ids), np.int64)
    rank[order] = np.arange(len(ids)) - np.repeat(starts, lengths)
    return rank


class Slots:
    """Rows of width w (faces: 3 corners, rim edges: 2 ends) kept in stable slots of a page's buffer.

    rows : (s, w) int64, the row in each slot; live : (s,) bool, whether the slot holds one
    """

    def __init__(self, rows, width: int):
        self.rows = np.array(rows, dtype=np.int64).reshape(len(rows), width)
        self.live = np.ones(len(self.rows), bool)

    @property
    def n_live(self) -> int:
        return int(self.live.sum())

    def update(self, new) -> tuple[np.ndarray, np.ndarray]:
        """Make the slots hold the rows ``new`` ((k, w) int, any order); returns the slots written
        ((q,) int64) and what each now holds ((q, w) int64; zeros where a slot was freed)."""
        new = np.asarray(new, dtype=np.int64).reshape(len(new), self.rows.shape[1])
        held = np.flatnonzero(self.live)
        both = np.concatenate((self.rows[held], new))
        if len(both) == 0:
            return np.empty(0, np.int64), np.empty((0, self.rows.shape[1]), np.int64)
        _, ids = np.unique(both, axis=0, return_inverse=True)
        ids = ids.reshape(-1).astype(np.int64)
        # (occurrences counted within each side: the k-th copy of a row matches the k-th copy)
        old_ids, new_ids = ids[:len(held)], ids[len(held):]
        old_keys = old_ids * (len(both) + 1) + _occurrences(old_ids)
        new_keys = new_ids * (len(both) + 1) + _occurrences(new_ids)
        freed = held[~np.isin(old_keys, new_keys)]
        added = new[~np.isin(new_keys, old_keys)]
        reused = min(len(freed), len(added))
        extra = np.arange(len(self.rows), len(self.rows) + len(added) - reused)
        slots = np.concatenate((freed[:reused], extra, freed[reused:]))
        values = np.concatenate((added, np.zeros((len(freed) - reused, self.rows.shape[1]), np.int64)))
        if len(extra):
            self.rows = np.concatenate((self.rows, np.zeros((len(extra), self.rows.shape[1]), np.int64)))
            self.live = np.concatenate((self.live, np.zeros(len(extra), bool)))
        self.rows[slots] = values
        self.live[slots] = np.arange(len(slots)) < len(added)
        return slots, values


def _vertex_arrays(rig) -> dict:
    """The per-vertex arrays a page holds of ``rig``: three.js attribute name -> ((n, k) values, dtype)."""
    arrays = {"position": (rig.vertices, "<f4"), "skinIndex": (rig.joints, "<u2"),
              "skinWeight": (rig.weights, "<f4")}
    for gltf, three in PAGE_ATTRIBUTES.items():
        if gltf in rig.attributes:
            values = np.asarray(rig.attributes[gltf])
            arrays[three] = (values.reshape(len(values), int(np.prod(values.shape[1:]))), "<f4")
    return arrays


class Mirror:
    """What one page holds of a session's mesh: starts as ``rig`` (the model the page loaded)."""

    def __init__(self, rig):
        self.rig = rig
        self.faces = Slots(rig.faces, 3)
        self.rims = Slots(rim_edges(rig), 2)

    def update(self, rig) -> dict:
        """The delta that brings the page from the mirrored rig to ``rig`` (JSON-ready), and mirror ``rig``.

        Returns {"n_vertices", "n_faces", "n_rims", "slots": face slots in use, "rim_slots",
        "rows": {"index": (k,) uint32 rows, <attribute>: (k, c) values of those rows, ...},
        "faces": {"slots": (q,) uint32, "corners": (q, 3) uint32}, "rims": {"slots", "ends": (r, 2)}}
        with the arrays base64-encoded (``encode``).
        """
        old, new = _vertex_arrays(self.rig), _vertex_arrays(rig)
        n0, n1 = self.rig.n_vertices, rig.n_vertices
        common = min(n0, n1)
        changed = np.zeros(common, bool)
        for name, (values, _) in new.items():
            if name not in old or old[name][0].shape[1:] != values.shape[1:]:
                changed[:] = True                # (an attribute the page did not have: every row)
                break
            changed |= (old[name][0][:common] != values[:common]).any(axis=1)      # (all (n, c))
        rows = np.concatenate((np.flatnonzero(changed), np.arange(common, n1)))
        face_slots, corners = self.faces.update(rig.faces)
        rim_slots, ends = self.rims.update(rim_edges(rig))
        self.rig = rig
        return {"n_vertices": int(n1), "n_faces": int(rig.n_faces), "n_rims": self.rims.n_live,
                "slots": len(self.faces.rows), "rim_slots": len(self.rims.rows),
                "rows": {"index": encode(rows, "<u4"),
                         **{name: encode(values[rows], dtype) for name, (values, dtype) in new.items()}},
                "faces": {"slots": encode(face_slots, "<u4"), "corners": encode(corners, "<u4")},
                "rims": {"slots": encode(rim_slots, "<u4"), "ends": encode(ends, "<u4")}}


def full_delta(rig) -> dict:
    """The delta that writes all of ``rig`` into an empty page: the size of sending the whole mesh
    in this encoding, what a delta is measured against."""
    empty = rig._with_checked_mesh(rig.vertices[:0], rig.faces[:0], rig.joints[:0], rig.weights[:0],
                                   {name: np.asarray(values)[:0] for name, values in rig.attributes.items()})
    return Mirror(empty).update(rig)
