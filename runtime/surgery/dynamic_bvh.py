"""A triangle BVH that an editing session keeps across strokes, updated locally (``DynamicBVH``).

A scalpel session on a 1.5M-face mesh makes hundreds of strokes, each replacing a few dozen faces by
their pieces: a ``TriangleBVH`` rebuild costs a second per stroke, an edit here O(k log m) for k faces.

Layout: the tree of ``bvh._build`` in node arrays that grow by doubling. A leaf owns a block of
slots (start, capacity) with its triangles' corners contiguous, the live ones first (count): remove
moves the leaf's last triangle into the hole, so queries never meet a dead slot. Insert descends
into the child whose box grows least (ties: the smaller box) and appends to the leaf, moving a full
block to the end with twice the room, up to LEAF_MAX (the old block is dead until a rebuild); a
leaf that would pass LEAF_MAX faces splits at the median centroid along the longest axis. An edit
refits its leaf and the ancestors up to the first unchanged box, padded like bvh.py (BOX_PADDING
times the scene extent at build). Dense face id -> slot and slot -> leaf maps find a face's leaf.
The edits are compiled in ``dynamic_bvh_edits.py``, as one kernel.

Degradation: the SAH cost (inner nodes weigh 1, leaves their count; over the root's area), kept at
every change, over its value after the last build; an edit rebuilds past ``REBUILD_AT`` (or when dead
slots outnumber live faces). Measured (``python -m benchmarks.bench_dynamic_bvh``, 2 cores,
capsule_arm 850 x 294 = 1.58M faces): build 1.2 s (static 0.7 s), memory
1.20x the static arrays; first_hit on 20k random segments 3.5 us (static 3.7 us); faces_near_plane
over 2352 faces 0.23 ms; a stroke (remove 30, insert 90 pieces, move 40) 0.25 ms median; 300 strokes
of an incision leave the degradation at 1.000 (first_hit 3.50 us, 3.42 us rebuilt). Strokes at random
places that also throw 40 faces ~20 face widths: degradation 1.35 / 1.86 / 2.29 / 2.78 / 4.13 / 7.58
after 150 / 300 / 450 / 600 / 1000 / 2000 strokes, first_hit 1.02 / 1.08 / 1.06 / 1.14 / 1.19 / 1.39x
that of a rebuilt tree (the SAH ratio also counts the faces' own growth, which no rebuild undoes):
at 3 (``REBUILD_AT``) queries are ~15 % slower than rebuilt; a rebuild costs ~300k queries.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array, index_array, real_number
from ..errors import InvalidInputError
from .bvh import BOX_PADDING, LEAF_SIZE, TriangleBVH, _all_hits, _faces_near_plane, _first_hit
from .bvh_build import _build
from .dynamic_bvh_edits import LEAF_MAX, _change

__all__ = ["DynamicBVH", "dyn_first_hit", "dyn_faces_near_plane", "LEAF_MAX", "REBUILD_AT"]

#: ``degradation`` (SAH relative to the last build) past which an edit rebuilds (measured above)
REBUILD_AT = 3.0


def _cost(st) -> float:
    """The SAH cost: the SAH sum over the root's area (0 for an empty tree)."""
    d = st[1][0] - st[0][0]
    area = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]) if d[0] >= 0.0 else 0.0
    return float(st[13][0] / area) if area > 0.0 else 0.0


# ---- queries: kernels that Python and other kernels call with ``DynamicBVH.arrays`` --------------
#: (face, t) of the first crossing of segment a -> b, the lowest face id among equal t, (-1, nan) if
#: none: ``bvh._first_hit`` reads ``arrays`` (leaves hold no dead slot; slot_face is its leaf order)
dyn_first_hit = _first_hit


#: the live faces (unsorted) within ``delta`` of a plane in a box: ``bvh._faces_near_plane``
dyn_faces_near_plane = _faces_near_plane


# ---- public object --------------------------------------------------------------------------------
def _grown(arr, size, fill, factor=2):
    """``arr`` with room for ``size`` rows (``factor`` times as many when it grows: amortised)."""
    if len(arr) >= size:
        return arr
    out = np.full((max(size, factor * len(arr)),) + arr.shape[1:], fill, arr.dtype)
    out[:len(arr)] = arr
    return out


class DynamicBVH:
    """A BVH over triangles that follows removals, insertions and moves of faces in place.

    positions : (n, 3) float ; faces : (m, 3) int, m >= 1, face ids 0 .. m-1 ; capacity : spare
    slots and nodes (default m / 16). Face ids are ints in [0, 2**31), new ones for insert. The BVH
    keeps its own corners; faces are two-sided; segments a -> b ((3,) points) as in ``TriangleBVH``.
    n_faces : live faces ; degradation : SAH cost / its value after the last build ; rebuilds : count
    """

    def __init__(self, positions, faces, capacity=None):
        positions = np.ascontiguousarray(float_array(positions, "positions", 3, ndim=2))
        faces = np.ascontiguousarray(index_array(faces, "faces", len(positions)), dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise InvalidInputError(f"faces must have shape (m, 3) with m >= 1, got {faces.shape}")
        self._spare = len(faces) // 16 + 64 if capacity is None else max(int(capacity), 0)
        self.rebuilds = 0
        self._load(positions, faces, np.arange(len(faces)))

    def _load(self, positions, faces, ids):
        """Adopt the tree of ``bvh._build`` over ``faces`` (named ``ids``), with spare room."""
        lo, hi, left, right, start, count, order, tri = _build(positions, faces, LEAF_SIZE, BOX_PADDING)
        m, rows, spare = len(order), len(lo) + self._spare // 2 + 16, self._spare
        pad = BOX_PADDING * max(float(np.ptp(tri.reshape(-1, 3), axis=0).max()), 1e-300)  # as _build
        corners = _grown(tri, m + spare, 0.0, 1)
        del tri                # (the largest array: let it go before the others are copied)
        parent = np.full(len(lo), -1)
        parent[left[left >= 0]] = parent[right[left >= 0]] = np.flatnonzero(left >= 0)
        leaves = np.flatnonzero(left < 0)[np.argsort(start[left < 0])]
        d = hi - lo       # the SAH sum: box areas, weighing 1 (inner nodes) or the count (leaves)
        sah = (d[:, 0] * d[:, 1] + d[:, 1] * d[:, 2] + d[:, 2] * d[:, 0]) @ np.where(left >= 0, 2.0, 2 * count)
        face_slot = np.full(ids.max() + 1 + spare, -1)
        face_slot[ids[order]] = np.arange(m)
        # st: lo, hi, left, right, parent, start, count, capacity (nodes); face, leaf, corners
        # (slots); slot of each face id; [nodes, slots, dead slots, live faces]; [SAH sum, padding]
        self._st = tuple(_grown(x, rows if len(x) == len(lo) else m + spare, fill, 1) for x, fill in (
            (lo, np.inf), (hi, -np.inf), (left, -1), (right, -1), (parent, -1), (start, -1), (count, 0),
            (count, 0), (ids[order], -1), (np.repeat(leaves, count[leaves]), -1))) + (
            corners,
            face_slot, np.array([len(lo), m, 0, m]), np.array([sah, pad]))
        self._sah0 = _cost(self._st)

    @property
    def n_faces(self) -> int:
        return int(self._st[12][3])

    @property
    def degradation(self) -> float:
        return _cost(self._st) / self._sah0 if self._sah0 > 0 else 1.0

    @property
    def arrays(self) -> tuple:
        """(lo, hi, left, right, start, count, slot_face, tri): the tree as compiled queries take it."""
        st = self._st
        return (st[0], st[1], st[2], st[3], st[5], st[6], st[8], st[10])

    def _ids(self, face_ids, name, live):
        """Distinct face ids (k,) int64, all live (``live``) or none live."""
        # ids index a dense map (8 bytes per id up to the largest one seen): bound them
        ids = np.ascontiguousarray(index_array(face_ids, name, 2 ** 31), dtype=np.int64)
        if ids.ndim != 1 or len(np.unique(ids)) != len(ids):
            raise InvalidInputError(f"{name} must be distinct face ids, shape (k,), got {ids[:8].tolist()}")
        face_slot = self._st[11]
        wrong = ids[((ids < len(face_slot)) & (face_slot[np.minimum(ids, len(face_slot) - 1)] >= 0)) != live]
        if len(wrong):
            raise InvalidInputError(f"{name} holds {'faces that are not live' if live else 'live faces'}: "
                                    f"{wrong[:8].tolist()}")
        return ids

    def triangle(self, face) -> np.ndarray:
        """(3, 3) corners of live ``face`` as the BVH holds them."""
        return self._st[10][self._st[11][self._ids([face], "face", True)[0]]].reshape(3, 3).copy()

    def remove(self, face_ids):
        """Remove live faces (k,): they are never hit again."""
        self._apply(face_ids, None, True)

    def update(self, face_ids, corners):
        """Give live faces (k,) new corners (k, 3, 3)."""
        self._apply(face_ids, corners, True)

    def insert(self, face_ids, corners, near=None):
        """Add faces with new ids (k,), none live, and corners (k, 3, 3); ``near`` (k,) optional live
        faces whose leaves take them (the faces they are pieces of; -1: descend from the root)."""
        self._apply(face_ids, corners, False, near)

    def _apply(self, face_ids, corners, live, near=None):
        ids = self._ids(face_ids, "face_ids", live)
        k = len(ids)
        if corners is not None:
            corners = float_array(corners, "corners", 3, ndim=3)
            if corners.shape != (k, 3, 3):
                raise InvalidInputError(f"corners must have shape ({k}, 3, 3), got {corners.shape}")
            corners = np.ascontiguousarray(corners.reshape(k, 9))
        if not k:
            return
        none, none9 = np.empty(0, np.int64), np.empty((0, 9))
        if live and corners is None:
            _change(self._st, none, none9, none, ids, none, none9)
        elif live:
            _change(self._st, none, none9, none, none, ids, corners)
        else:
            near = np.full(k, -1, np.int64) if near is None else np.ascontiguousarray(near, dtype=np.int64)
            given, face_slot = near[near >= 0], self._st[11]
            if near.shape != (k,) or (given >= len(face_slot)).any() or (face_slot[given] < 0).any():
                raise InvalidInputError(f"near must hold ({k},) live faces or -1, got {near[:8].tolist()}")
            self._make_room(k, int(ids.max()))
            _change(self._st, ids, corners, near, none, none, none9)
        self._rebuild_if_degraded()

    def _make_room(self, k: int, top_id: int) -> None:
        """Room for inserting k faces, ids up to ``top_id``: the worst case, per face two nodes and a
        new block of LEAF_MAX slots (arrays grow by doubling)."""
        st = list(self._st)
        st[11] = _grown(st[11], top_id + 1, -1)
        for j, fill in enumerate((np.inf, -np.inf, -1, -1, -1, -1, 0, 0)):
            st[j] = _grown(st[j], st[12][0] + 2 * k, fill)
        for j, fill in ((8, -1), (9, -1), (10, 0.0)):
            st[j] = _grown(st[j], st[12][1] + LEAF_MAX * k, fill)
        self._st = tuple(st)

    def _rebuild_if_degraded(self) -> None:
        if self.degradation > REBUILD_AT or self._st[12][2] > max(self._st[12][3], 1024):
            self.rebuild()

    def edit(self, removed, inserted, corners, near, moved, moved_corners) -> None:
        """One stroke's changes at once, WITHOUT the checks of ``remove``/``insert``/``update`` (whose
        cost is a tenth of a stroke on a small mesh): for a caller that owns its face ids (the editing
        session). inserted (k,) new ids with corners (k, 9) and near (k,) live faces (their leaves take
        them) go in first, then removed (r,) live faces out, then moved (u,) live faces get
        moved_corners (u, 9). All int64 / float64, C-contiguous."""
        if len(inserted):
            self._make_room(len(inserted), int(inserted.max()))
        _change(self._st, inserted, corners, near, removed, moved, moved_corners)
        self._rebuild_if_degraded()

    def rebuild(self):
        """Build afresh from the live triangles, keeping their face ids."""
        slot_face, tri = self._st[8], self._st[10]
        live = np.flatnonzero(slot_face[:self._st[12][1]] >= 0)
        self.rebuilds += 1
        if len(live):           # with no face left, the empty tree answers every query
            self._spare = max(self._spare, len(live) // 16 + 64)
            self._load(np.ascontiguousarray(tri[live].reshape(-1, 3)),
                       np.arange(3 * len(live)).reshape(-1, 3), slot_face[live])

    def first_hit(self, a, b) -> tuple[int, float]:
        """(face, t) of the first crossing of a -> b, the lowest face id among equal t; (-1, nan)."""
        face, t = dyn_first_hit(self.arrays, *TriangleBVH._segment(a, b))
        return int(face), float(t)

    def all_hits(self, a, b) -> tuple[np.ndarray, np.ndarray]:
        """Every crossing of a -> b: (faces (k,), t (k,)) sorted by t, then face id."""
        # the leaves hold no dead slot, so bvh's traversal reads slot_face as its leaf order
        faces, ts = _all_hits(self.arrays, *TriangleBVH._segment(a, b))
        order = np.lexsort((faces, ts))
        return faces[order], ts[order]

    def faces_near_plane(self, lo, hi, normal, offset, delta) -> np.ndarray:
        """Sorted live faces whose triangle box meets the closed box [lo, hi] and whose corners'
        s = normal . x - offset have min(s) <= delta and max(s) >= -delta (never misses one)."""
        lo, hi, normal = (float_array(x, name, 3, ndim=1)
                          for x, name in ((lo, "lo"), (hi, "hi"), (normal, "normal")))
        if real_number(delta, "delta") < 0:
            raise InvalidInputError(f"delta must be >= 0, got {delta}")
        return np.sort(dyn_faces_near_plane(self.arrays, lo, hi, normal, real_number(offset, "offset"),
                                            float(delta)))

    def faces_in_box(self, lo, hi) -> np.ndarray:
        """Sorted live faces whose triangle box meets the closed box [lo, hi]."""
        return self.faces_near_plane(lo, hi, np.zeros(3), 0.0, 0.0)
