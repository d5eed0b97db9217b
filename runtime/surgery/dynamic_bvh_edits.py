"""The edits of ``dynamic_bvh.DynamicBVH`` in compiled code (the design is in dynamic_bvh.py): insert
beside a face or by least-growth descent, remove by moving a leaf's last face into the hole, refit
up to the first unchanged box (after a face's corners moved), split a full leaf at its median
centroid; and the adoption of a built tree. ``st`` is a ``TreeState`` as a plain tuple (the kernels
unpack it in field order); the tree reads a face's corners as positions[faces[face]] from its
``positions`` and ``faces``.
"""
from typing import NamedTuple

import numpy as np

from .._shared.jit import F1, F2, I1, I2, helper, i8, kernel, record
from .bvh_build import N1

#: a leaf that would hold more live faces than this is split
LEAF_MAX = 16
#: the entries of ``TreeState.counts``: node rows and slots in use, dead slots, live faces
NODES, SLOTS, DEAD, LIVE = 0, 1, 2, 3
#: the entries of ``TreeState.sums``: the SAH sum (inner nodes weigh 1, leaves their count), the padding
SAH, PADDING = 0, 1


class TreeState(NamedTuple):
    """A ``DynamicBVH``'s arrays (compiled code takes ``tuple(state)``).

    lo, hi : (N, 3) float64 node boxes ; left, right, parent, start, count, capacity : (N,) int32 per
    node row (children or -1, parent or -1, a leaf's block of slots and its live faces)
    slot_face, slot_leaf : (S,) int32 the face id and the leaf of each slot
    positions : (n, 3) float64, faces : (F, 3) int64 the caller's arrays the corners are read from
    face_slot : (I,) int32 the slot of each face id (-1: none)
    counts : (4,) int64 (``NODES``, ``SLOTS``, ``DEAD``, ``LIVE``) ; sums : (2,) float64 (``SAH``, ``PADDING``)
    """

    lo: np.ndarray
    hi: np.ndarray
    left: np.ndarray
    right: np.ndarray
    parent: np.ndarray
    start: np.ndarray
    count: np.ndarray
    capacity: np.ndarray
    slot_face: np.ndarray
    slot_leaf: np.ndarray
    positions: np.ndarray
    faces: np.ndarray
    face_slot: np.ndarray
    counts: np.ndarray
    sums: np.ndarray


#: the numba type of a ``TreeState`` as kernels take it (for precompile signatures)
STATE = record(F2, F2, N1, N1, N1, N1, N1, N1, N1, N1, F2, I2, N1, I1, F1)


@helper
def _area(lo, hi, i):
    """Surface area of box i of lo, hi (N, 3); 0 for an empty box (lo = inf, hi = -inf). Scalar
    reads: a row view would cost a reference count, which dominated the descent."""
    dx, dy, dz = hi[i, 0] - lo[i, 0], hi[i, 1] - lo[i, 1], hi[i, 2] - lo[i, 2]
    return 2.0 * (dx * dy + dy * dz + dz * dx) if dx >= 0.0 else 0.0


@helper
def _growth(lo, hi, i, b):
    """How much box i's area grows when it takes in box b (2, 3) (rows lo, hi); and box i's area."""
    area = _area(lo, hi, i)
    if lo[i, 0] > hi[i, 0]:
        return _area(b[:1], b[1:], 0), area
    ux = max(hi[i, 0], b[1, 0]) - min(lo[i, 0], b[0, 0])
    uy = max(hi[i, 1], b[1, 1]) - min(lo[i, 1], b[0, 1])
    uz = max(hi[i, 2], b[1, 2]) - min(lo[i, 2], b[0, 2])
    return 2.0 * (ux * uy + uy * uz + uz * ux) - area, area


@kernel((N1, N1, N1, N1, F2, F2, N1, i8, i8), cost=0.6)
def _adopt(left, right, start, count, lo, hi, slot_face, n_nodes, n_ids):
    """The fields a DynamicBVH adds to the tree of ``bvh_build._build`` (its first ``n_nodes`` rows;
    ``slot_face`` (s,) the faces of its leaf order, with spare room past them): parent and capacity per
    node row, leaf per slot (both with the same spare room, unwritten), slot per face id (n_ids, -1
    where none), and the SAH sum (inner nodes weigh 1, leaves their count)."""
    parent = np.empty(left.shape[0], np.int32)
    cap = np.empty(left.shape[0], np.int32)
    slot_leaf = np.empty(slot_face.shape[0], np.int32)
    face_slot = np.full(n_ids, -1, np.int32)
    parent[0] = -1
    sah = 0.0
    for node in range(n_nodes):
        cap[node] = count[node]
        if left[node] >= 0:
            parent[left[node]] = parent[right[node]] = node
            sah += _area(lo, hi, node)
        else:
            sah += count[node] * _area(lo, hi, node)
            for s in range(start[node], start[node] + count[node]):
                slot_leaf[s] = node
                face_slot[slot_face[s]] = s
    return parent, cap, slot_leaf, face_slot, sah


@helper
def _refit(st, node, n):
    """Give leaf ``node`` the live count n, recompute its box and its ancestors' up to the first
    that does not change; keeps the SAH sum (inner nodes weigh 1, leaves their count)."""
    nlo, nhi, left, right, parent, start, count, _, slot_face, _, positions, faces, _, _, sums = st
    sums[SAH] += (n - count[node]) * _area(nlo, nhi, node)
    count[node] = n
    box = np.empty((2, 3))
    while node >= 0:
        if left[node] < 0:
            box[0], box[1] = np.inf, -np.inf
            for s in range(start[node], start[node] + count[node]):
                f = slot_face[s]
                for c in range(3):
                    v = faces[f, c]
                    for k in range(3):
                        box[0, k] = min(box[0, k], positions[v, k])
                        box[1, k] = max(box[1, k], positions[v, k])
            if count[node] > 0:
                box[0] -= sums[PADDING]        # the padding, as bvh._build pads
                box[1] += sums[PADDING]
        else:
            for k in range(3):
                box[0, k] = min(nlo[left[node], k], nlo[right[node], k])
                box[1, k] = max(nhi[left[node], k], nhi[right[node], k])
        same = True
        for k in range(3):
            same = same and box[0, k] == nlo[node, k] and box[1, k] == nhi[node, k]
        if same:
            return
        w = 1.0 if left[node] >= 0 else float(count[node])
        sums[SAH] -= w * _area(nlo, nhi, node)
        for k in range(3):
            nlo[node, k], nhi[node, k] = box[0, k], box[1, k]
        sums[SAH] += w * _area(nlo, nhi, node)
        node = parent[node]


@kernel((STATE, I1, I1, I1, I1), cost=8.0)
def _change(st, inserted, near, removed, moved):
    """Every edit of the tree, in one kernel: insert the faces ``inserted`` (k,) beside ``near`` (k,),
    then remove ``removed``, then refit ``moved`` (whose corners changed in st's positions and faces).

    returns (done, cost, dead, live): done False, with nothing changed, when the arrays lack room for
    the insertion (the caller grows them and calls again); the SAH cost after the edits (the SAH sum
    over the root's area, 0 for an empty tree), the dead slots and the live faces (what the caller's
    rebuild test reads: from Python, each of them cost a numpy call)
    """
    nlo, nhi, _, _, _, _, _, _, slot_face, _, _, _, face_slot, counts, sums = st
    top = -1
    for f in inserted:
        top = max(top, f)
    k = inserted.shape[0]
    if (top >= face_slot.shape[0] or counts[NODES] + 2 * k > nlo.shape[0]
            or counts[SLOTS] + LEAF_MAX * k > slot_face.shape[0]):
        return False, 0.0, counts[DEAD], counts[LIVE]
    _insert(st, inserted, near)
    _edit(st, removed, True)
    _edit(st, moved, False)
    area = _area(nlo, nhi, 0)
    return True, sums[SAH] / area if area > 0.0 else 0.0, counts[DEAD], counts[LIVE]


@helper
def _put(st, s, leaf, face):
    _, _, _, _, _, _, _, _, slot_face, slot_leaf, _, _, face_slot, _, _ = st
    slot_face[s], slot_leaf[s], face_slot[face] = face, leaf, s


@helper
def _edit(st, faces, remove):
    """Remove ``faces`` (``remove``) or refit their leaves to their corners now: each leaf they are in
    refit once, after its faces are all removed (a hole removes a leaf's faces a dozen at a time)."""
    nlo, nhi, _, _, _, start, count, _, slot_face, slot_leaf, _, _, face_slot, counts, sums = st
    leaves = np.empty(faces.shape[0], np.int32)
    for i in range(faces.shape[0]):
        s = face_slot[faces[i]]
        leaf = slot_leaf[s]
        leaves[i] = leaf
        if remove:
            last = start[leaf] + count[leaf] - 1
            if s != last:    # keep the leaf's live faces first: its last one fills the hole
                _put(st, s, leaf, slot_face[last])
            slot_face[last] = face_slot[faces[i]] = -1
            counts[LIVE] -= 1
            sums[SAH] -= _area(nlo, nhi, leaf)        # one face less in the leaf's (old) box
            count[leaf] -= 1
    leaves.sort()
    for i in range(leaves.shape[0]):
        if i == 0 or leaves[i] != leaves[i - 1]:
            _refit(st, leaves[i], count[leaves[i]])


@helper
def _face_box(positions, faces, f, pad, box):
    """box (2, 3) := the bounding box of face f's corners, padded by ``pad``."""
    for k in range(3):
        a, b, c = positions[faces[f, 0], k], positions[faces[f, 1], k], positions[faces[f, 2], k]
        box[0, k] = min(a, min(b, c)) - pad
        box[1, k] = max(a, max(b, c)) + pad


@helper
def _insert(st, inserted, near):
    """Insert the faces ``inserted``, each into the leaf of the live face ``near[i]`` (a piece of it:
    no descent) or, where near[i] is -1, into the leaf the least-growth descent finds from the lowest
    node above the previous face's leaf that holds the face's box (the root when none does): faces
    inserted together usually lie together, and a node that holds a box grows by nothing for it."""
    (nlo, nhi, left, right, parent, start, count, cap, slot_face, slot_leaf, positions, faces, face_slot, counts,
     sums) = st
    box = np.empty((2, 3))
    previous = 0
    for i in range(inserted.shape[0]):
        _face_box(positions, faces, inserted[i], sums[PADDING], box)
        node = previous if near[i] < 0 else slot_leaf[face_slot[near[i]]]
        while near[i] < 0 and node != 0 and not _holds_box(nlo, nhi, node, box):
            node = parent[node]
        while left[node] >= 0:
            gl, al = _growth(nlo, nhi, left[node], box)
            gr, ar = _growth(nlo, nhi, right[node], box)
            node = left[node] if gl < gr or (gl == gr and al <= ar) else right[node]
        n = count[node]
        if n == LEAF_MAX:
            _split(st, node, inserted[i])
        else:
            if n == cap[node]:
                # move the full block to the end with twice the room (amortised O(1) per face); the
                # room past the live faces holds no face (-1: slots past counts[SLOTS] are unwritten)
                room = min(max(2 * cap[node], 2), LEAF_MAX)
                for j in range(n):
                    _put(st, counts[SLOTS] + j, node, slot_face[start[node] + j])
                    slot_face[start[node] + j] = -1
                slot_face[counts[SLOTS] + n:counts[SLOTS] + room] = -1
                counts[DEAD] += cap[node]
                start[node], cap[node] = counts[SLOTS], room
                counts[SLOTS] += room
            _put(st, start[node] + n, node, inserted[i])
            _refit(st, node, n + 1)
        counts[LIVE] += 1
        previous = slot_leaf[face_slot[inserted[i]]]


@helper
def _holds_box(lo, hi, i, box):
    """Whether node i's box (rows of lo, hi (N, 3)) holds box (2, 3)."""
    return (lo[i, 0] <= box[0, 0] and lo[i, 1] <= box[0, 1] and lo[i, 2] <= box[0, 2]
            and hi[i, 0] >= box[1, 0] and hi[i, 1] >= box[1, 1] and hi[i, 2] >= box[1, 2])


@helper
def _split(st, leaf, face):
    """Split a full leaf plus one new face into two new leaves at the median centroid."""
    (nlo, nhi, left, right, parent, start, count, cap, slot_face, slot_leaf, positions, faces, face_slot, counts,
     sums) = st
    n, at = count[leaf] + 1, start[leaf]
    ids = np.empty(n, np.int64)
    for j in range(n - 1):
        ids[j] = slot_face[at + j]
    ids[n - 1] = face
    # (3 x) the centroids, the longest axis of them, then a stable insertion sort along it (n <= 9):
    # loops, not numpy calls, which numba compiles in seconds
    cs = np.empty((n, 3))
    for j in range(n):
        p, q, r = faces[ids[j], 0], faces[ids[j], 1], faces[ids[j], 2]
        for k in range(3):
            cs[j, k] = (positions[p, k] + positions[q, k]) + positions[r, k]
    axis, widest = 0, -1.0
    for k in range(3):
        lo_k, hi_k = np.inf, -np.inf
        for j in range(n):
            lo_k, hi_k = min(lo_k, cs[j, k]), max(hi_k, cs[j, k])
        if hi_k - lo_k > widest:
            axis, widest = k, hi_k - lo_k
    order = np.arange(n)
    for j in range(1, n):
        o = order[j]
        key = cs[o, axis]
        i = j
        while i > 0 and cs[order[i - 1], axis] > key:
            order[i] = order[i - 1]
            i -= 1
        order[i] = o
    sums[SAH] += (1 - count[leaf]) * _area(nlo, nhi, leaf)    # an inner node weighs 1, a leaf its count
    a, new = counts[NODES], counts[SLOTS]
    counts[NODES], counts[SLOTS] = a + 2, new + LEAF_MAX
    left[leaf], right[leaf], count[leaf] = a, a + 1, 0
    nlo[a:a + 2], nhi[a:a + 2] = np.inf, -np.inf     # empty until filled: the first refit sees no junk
    for c in range(2):
        at, room, lo_i, hi_i = start[leaf], cap[leaf], 0, n // 2
        if c == 1:
            at, room, lo_i, hi_i = new, LEAF_MAX, n // 2, n
        left[a + c], right[a + c], parent[a + c] = -1, -1, leaf
        start[a + c], cap[a + c], count[a + c] = at, room, 0
        for j in range(lo_i, hi_i):
            _put(st, at + j - lo_i, a + c, ids[order[j]])
        slot_face[at + hi_i - lo_i:at + room] = -1
        _refit(st, a + c, hi_i - lo_i)
