"""A triangle BVH that an editing session keeps across strokes, updated locally (``DynamicBVH``).

A scalpel session on a mesh of millions of faces makes hundreds of strokes, each replacing a few
dozen faces by their pieces: a ``TriangleBVH`` rebuild per stroke would cost far more than the
stroke, an edit here O(k log m) for k faces.

Layout: the tree of ``bvh_build._build`` in node arrays that grow by doubling (int32 indices). The
BVH owns no geometry: it reads face f's corners as positions[faces[f]] from the caller's arrays (the
session's own mesh buffers), so that its memory is the tree's (~40 bytes a face; the spare rows are
allocated, not written, so not resident until used). A leaf owns a block of slots (start, capacity)
holding face ids, the live ones first (count): remove moves the leaf's last face into the hole, so
queries never meet a dead slot. Insert descends into the child whose box grows least (ties: the
smaller box) and appends to the leaf, moving a full block to the end with twice the room, up to
LEAF_MAX (the old block is dead until a rebuild); a leaf that would pass LEAF_MAX faces splits at
the median centroid along the longest axis. An edit
refits its leaf and the ancestors up to the first unchanged box, padded like bvh.py (BOX_PADDING
times the scene extent at build). Dense face id -> slot and slot -> leaf maps find a face's leaf.
The edits are compiled in ``dynamic_bvh_edits.py``, as one kernel.

Degradation: the SAH cost (inner nodes weigh 1, leaves their count; over the root's area), kept at
every change, over its value after the last build; an edit rebuilds past ``REBUILD_AT`` (or when dead
slots outnumber live faces). Leaves hold 8 faces at build rather than 4: a smaller tree, with queries
as fast and edits as cheap (``python -m benchmarks.bench_dynamic_bvh`` measures memory, queries and
edits). An incision's strokes leave the degradation near 1; strokes that also move faces' corners
raise it steadily (the SAH ratio also counts the faces' own growth, which no rebuild undoes), and at
``REBUILD_AT`` queries have become clearly slower than a rebuilt tree's while one rebuild still costs
as much as a great many queries. An editing session's peak memory is its mesh buffers and this tree,
the build's temporaries setting the peak (``python -m benchmarks.bench_progressive``).
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array, index_array, real_number
from .._shared.ids import ascending
from ..errors import InvalidInputError
from .bvh import BOX_PADDING, TriangleBVH, _all_hits, _faces_near_plane, _first_hit
from .bvh_build import _build
from .dynamic_bvh_edits import LEAF_MAX, LIVE, NODES, SAH, SLOTS, TreeState, _adopt, _change

__all__ = ["DynamicBVH", "dyn_first_hit", "dyn_faces_near_plane", "LEAF_MAX", "REBUILD_AT"]

#: faces per leaf at build: half of ``LEAF_MAX``, room to grow before a split. 8, twice a static
#: tree's (``bvh.LEAF_SIZE``): half the nodes, so half the tree's memory and of the bone influences a
#: posed stroke keeps per node, and fewer posed boxes a stroke in a new pose computes; queries and
#: edits measured the same (module docstring)
LEAF_SIZE = LEAF_MAX // 2

#: ``degradation`` (SAH relative to the last build) past which an edit rebuilds (measured above)
REBUILD_AT = 3.0

#: where a ``TreeState``'s positions are, followed by its faces
_POSITIONS = TreeState._fields.index("positions")
assert TreeState._fields[_POSITIONS + 1] == "faces"


def _cost(st: TreeState) -> float:
    """The SAH cost: the SAH sum over the root's area (0 for an empty tree; ``_change`` returns it)."""
    (x0, y0, z0), (x1, y1, z1) = st.lo[0].tolist(), st.hi[0].tolist()
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    area = 2.0 * (dx * dy + dy * dz + dz * dx) if dx >= 0.0 else 0.0
    return float(st.sums[SAH]) / area if area > 0.0 else 0.0


# ---- queries: kernels that Python and other kernels call with ``DynamicBVH.arrays`` --------------
#: (face, t) of the first crossing of segment a -> b, the lowest face id among equal t, (-1, nan) if
#: none: ``bvh._first_hit`` reads ``arrays`` (leaves hold no dead slot; slot_face is its leaf order)
dyn_first_hit = _first_hit


#: the live faces (unsorted) within ``delta`` of a plane in a box: ``bvh._faces_near_plane``
dyn_faces_near_plane = _faces_near_plane


# ---- public object --------------------------------------------------------------------------------
def _grown(arr, size, used, fill=None):
    """``arr`` with room for ``size`` rows (twice as many when it grows: amortised), its first ``used``
    rows kept; the new rows hold ``fill``, or are left unwritten (not resident until used)."""
    if len(arr) >= size:
        return arr
    shape = (max(size, 2 * len(arr)),) + arr.shape[1:]
    out = np.empty(shape, arr.dtype) if fill is None else np.full(shape, fill, arr.dtype)
    out[:used] = arr[:used]
    return out


def _geometry(ids, positions, faces):
    """``positions`` (n, 3) float64 and ``faces`` (F, 3) int64 as the BVH reads them (C-contiguous;
    converted copies only where they are not so), the triangles of face ``ids`` checked: rows of
    ``faces`` that index ``positions``, finite corners. O(len(ids)): the rest is the caller's word."""
    positions, faces = np.asarray(positions), np.asarray(faces)
    if positions.ndim != 2 or positions.shape[1] != 3 or positions.dtype.kind not in "fiu":
        raise InvalidInputError(f"positions must be a real (n, 3) array, got {positions.shape} {positions.dtype}")
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu":
        raise InvalidInputError(f"faces must be an integer (F, 3) array, got {faces.shape} {faces.dtype}")
    positions = np.ascontiguousarray(positions, dtype=np.float64)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if len(ids) and ids.max() >= len(faces):
        raise InvalidInputError(f"faces has {len(faces)} rows: no row for face {ids.max()}")
    rows = faces[ids]
    if rows.size and (rows.min() < 0 or rows.max() >= len(positions)):
        raise InvalidInputError(f"faces {ids[:8].tolist()} must index the {len(positions)} positions, got "
                                f"indices from {rows.min()} to {rows.max()}")
    if not np.isfinite(positions[rows]).all():
        raise InvalidInputError("positions holds a non-finite value (NaN or inf) at a corner of the faces given")
    return positions, faces


class DynamicBVH:
    """A BVH over triangles that follows removals, insertions and moves of faces in place.

    positions : (n, 3) float ; faces : (m, 3) int, m >= 1, face ids 0 .. m-1 ; capacity : spare
    slots and nodes (default m / 16). Face ids are ints in [0, 2**31), new ones for insert.

    The BVH holds no geometry of its own: it reads face f's corners as positions[faces[f]] from the
    arrays it was last given (float64 and int64 C-contiguous ones as they are, others as converted
    copies); it never writes them. Whoever edits them tells the BVH, passing the arrays as they are
    then: ``insert`` (new faces), ``update`` (faces whose corners moved), ``edit`` (a stroke's
    changes, unchecked), ``use`` (a copy of the same triangles); every other live face must keep its
    triangle. Faces are two-sided; segments a -> b ((3,) points) as in ``TriangleBVH``.
    n_faces : live faces ; degradation : SAH cost / its value after the last build ; rebuilds : count
    """

    def __init__(self, positions, faces, capacity=None):
        positions = np.ascontiguousarray(float_array(positions, "positions", 3, ndim=2))
        faces = np.ascontiguousarray(index_array(faces, "faces", len(positions)), dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise InvalidInputError(f"faces must have shape (m, 3) with m >= 1, got {faces.shape}")
        self._spare = len(faces) // 16 + 64 if capacity is None else max(int(capacity), 0)
        self.rebuilds = 0
        self._load(positions, faces, np.arange(len(faces), dtype=np.int32))

    def _load(self, positions, faces, ids):
        """Adopt the tree of ``bvh_build._build`` over the faces ``ids`` (k,) int32, with spare room
        (allocated, not written: resident only once used)."""
        k, spare = len(ids), self._spare
        slot_face = np.empty(k + spare, np.int32)
        slot_face[:k] = ids
        lo, hi, left, right, start, count, n_nodes, pad = _build(positions, faces, slot_face[:k], LEAF_SIZE,
                                                                 BOX_PADDING, spare // 2 + 16)
        parent, cap, slot_leaf, face_slot, sah = _adopt(left, right, start, count, lo, hi, slot_face, n_nodes,
                                                        int(ids.max()) + 1 + spare)
        self._st = TreeState(lo, hi, left, right, parent, start, count, cap, slot_face, slot_leaf, positions,
                             faces, face_slot, counts=np.array([n_nodes, k, 0, k]), sums=np.array([sah, pad]))
        self._sah0 = _cost(self._st)

    @property
    def n_faces(self) -> int:
        return int(self._st.counts[LIVE])

    @property
    def n_nodes(self) -> int:
        """Node rows in use (the arrays' rows past them are spare)."""
        return int(self._st.counts[NODES])

    @property
    def parents(self) -> np.ndarray:
        """(N,) int32 parent of each node row (-1 for the root)."""
        return self._st.parent

    def leaves(self, face_ids) -> np.ndarray:
        """(k,) int64 the leaf that holds each of the live faces ``face_ids`` (k,) int64 (unchecked)."""
        st = self._st
        return st.slot_leaf[st.face_slot[face_ids]].astype(np.int64)

    @property
    def degradation(self) -> float:
        return _cost(self._st) / self._sah0 if self._sah0 > 0 else 1.0

    @property
    def nbytes(self) -> int:
        """Bytes of the BVH's own arrays in use (the rows allocated past them are unwritten, so not
        resident; the positions and faces are the caller's)."""
        st = self._st
        nodes, slots = st.counts[NODES], st.counts[SLOTS]
        return int(sum(x[:nodes].nbytes for x in (st.lo, st.hi, st.left, st.right, st.parent, st.start, st.count,
                                                  st.capacity))
                   + st.slot_face[:slots].nbytes + st.slot_leaf[:slots].nbytes + st.face_slot.nbytes)

    @property
    def arrays(self) -> tuple:
        """(lo, hi, left, right, start, count, slot_face, positions, faces): the tree as compiled queries
        take it (``bvh.BVHArrays``)."""
        st = self._st
        return (st.lo, st.hi, st.left, st.right, st.start, st.count, st.slot_face, st.positions, st.faces)

    def _ids(self, face_ids, name, live):
        """Distinct face ids (k,) int64, all live (``live``) or none live."""
        # ids index a dense int32 map (4 bytes per id up to the largest one seen): bound them
        ids = np.ascontiguousarray(index_array(face_ids, name, 2 ** 31), dtype=np.int64)
        if ids.ndim != 1 or len(np.unique(ids)) != len(ids):
            raise InvalidInputError(f"{name} must be distinct face ids, shape (k,), got {ids[:8].tolist()}")
        face_slot = self._st.face_slot
        wrong = ids[((ids < len(face_slot)) & (face_slot[np.minimum(ids, len(face_slot) - 1)] >= 0)) != live]
        if len(wrong):
            raise InvalidInputError(f"{name} holds {'faces that are not live' if live else 'live faces'}: "
                                    f"{wrong[:8].tolist()}")
        return ids

    def triangle(self, face) -> np.ndarray:
        """(3, 3) corners of live ``face`` as the BVH reads them."""
        st = self._st
        return st.positions[st.faces[self._ids([face], "face", True)[0]]]

    def remove(self, face_ids):
        """Remove live faces (k,): they are never hit again."""
        ids, none = self._ids(face_ids, "face_ids", True), np.empty(0, np.int64)
        if len(ids):
            self._edit_tree(none, none, ids, none)

    def update(self, face_ids, positions, faces):
        """Live faces (k,) whose corners moved: they now are positions[faces[f]] (positions (n, 3),
        faces (F, 3), the arrays the BVH reads from now on)."""
        ids = self._ids(face_ids, "face_ids", True)
        (positions, faces), none = _geometry(ids, positions, faces), np.empty(0, np.int64)
        self._read_from(positions, faces)
        self._edit_tree(none, none, none, ids)

    def insert(self, face_ids, positions, faces, near=None):
        """Add faces with new ids (k,), none live, with corners positions[faces[f]] (the arrays the BVH
        reads from now on); ``near`` (k,) optional live faces whose leaves take them (the faces they
        are pieces of; -1: descend from the root)."""
        ids = self._ids(face_ids, "face_ids", False)
        k = len(ids)
        near = np.full(k, -1, np.int64) if near is None else np.ascontiguousarray(near, dtype=np.int64)
        given, face_slot = near[near >= 0], self._st.face_slot
        if near.shape != (k,) or (given >= len(face_slot)).any() or (face_slot[given] < 0).any():
            raise InvalidInputError(f"near must hold ({k},) live faces or -1, got {near[:8].tolist()}")
        positions, faces = _geometry(ids, positions, faces)
        self._read_from(positions, faces)
        if k:
            self._edit_tree(ids, near, np.empty(0, np.int64), np.empty(0, np.int64))

    def use(self, positions, faces) -> None:
        """Read the triangles from ``positions`` (n, 3) float64 and ``faces`` (F, 3) int64, C-contiguous,
        from now on: arrays that hold every live face's triangle as the last ones did (a copy that the
        caller goes on to edit). Unchecked, like ``edit``."""
        self._read_from(positions, faces)

    def _read_from(self, positions, faces) -> None:
        """Read the corners from ``positions`` and ``faces`` from now on (per stroke: a tuple's slices,
        a third of ``_replace``'s cost)."""
        st = self._st
        self._st = TreeState._make(st[:_POSITIONS] + (positions, faces) + st[_POSITIONS + 2:])

    def _edit_tree(self, inserted, near, removed, moved) -> None:
        """``_change`` with room made first where it lacks it, then a rebuild if the tree degraded."""
        done, cost, dead, live = _change(tuple(self._st), inserted, near, removed, moved)
        if not done:
            self._make_room(len(inserted), int(inserted.max()))
            done, cost, dead, live = _change(tuple(self._st), inserted, near, removed, moved)
        if (cost / self._sah0 if self._sah0 > 0 else 1.0) > REBUILD_AT or dead > max(live, 1024):
            self.rebuild()

    def _make_room(self, k: int, top_id: int) -> None:
        """Room for inserting k faces, ids up to ``top_id``: the worst case, per face two nodes and a
        new block of LEAF_MAX slots (arrays grow by doubling)."""
        st = self._st
        nodes, slots = int(st.counts[NODES]), int(st.counts[SLOTS])
        per_node = ("lo", "hi", "left", "right", "parent", "start", "count", "capacity")
        grown = {name: _grown(getattr(st, name), nodes + 2 * k, nodes) for name in per_node}
        for name in ("slot_face", "slot_leaf"):
            grown[name] = _grown(getattr(st, name), slots + LEAF_MAX * k, slots)
        grown["face_slot"] = _grown(st.face_slot, top_id + 1, len(st.face_slot), -1)
        self._st = st._replace(**grown)

    def edit(self, removed, inserted, near, moved, positions, faces) -> None:
        """One stroke's changes at once, WITHOUT the checks of ``remove``/``insert``/``update`` (whose
        cost is a tenth of a stroke on a small mesh): for a caller that owns its face ids and arrays
        (the editing session). ``positions`` (n, 3) float64 and ``faces`` (F, 3) int64, C-contiguous,
        hold every face named here and every live one (the BVH reads them from now on); inserted (k,)
        new ids go in first, each into the leaf of the live face near (k,) (-1: descend), then
        removed (r,) live faces out, then moved (u,) live faces, whose corners changed, are refitted.
        Ids int64, C-contiguous."""
        self._read_from(positions, faces)
        self._edit_tree(inserted, near, removed, moved)

    def rebuild(self):
        """Build afresh from the live faces, keeping their face ids, reading their triangles from the
        arrays last given."""
        st = self._st
        live = st.slot_face[:st.counts[SLOTS]]
        live = live[live >= 0]
        self.rebuilds += 1
        if len(live):           # with no face left, the empty tree answers every query
            self._spare = max(self._spare, len(live) // 16 + 64)
            positions, faces = st.positions, st.faces
            self._st = st = None        # the old tree goes before the new one is built (a lower peak)
            self._load(positions, faces, live)

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
        return ascending(dyn_faces_near_plane(self.arrays, lo, hi, normal, real_number(offset, "offset"),
                                              float(delta)))

    def faces_in_box(self, lo, hi) -> np.ndarray:
        """Sorted live faces whose triangle box meets the closed box [lo, hi]."""
        return self.faces_near_plane(lo, hi, np.zeros(3), 0.0, 0.0)
