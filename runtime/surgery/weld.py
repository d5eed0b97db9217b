"""Welding: which vertices of a mesh are one, by bitwise-equal position (and, for the tear, equal
label). A hash table in one numba pass (open addressing, linear probing, at least twice the keys so
that probes stay short); welded vertices are numbered by first appearance, each represented by its
lowest vertex. ``topology.py`` builds the welded topology on it."""
import numpy as np

from .._shared.jit import U2, helper, kernel

_M1 = np.uint64(0xFF51AFD7ED558CCD)
_M2 = np.uint64(0xC4CEB9FE1A85EC53)
_S33 = np.uint64(33)
#: odd multipliers that spread each key column before they are combined (then one finaliser: five
#: finalisers per key cost a third of a stroke's weld)
_K = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xC2B2AE3D27D4EB4F), np.uint64(0x165667B19E3779F9),
      np.uint64(0xD6E8FEB86659FD93))


@helper
def _mix(h):
    """The 64-bit finaliser of MurmurHash3: every input bit affects every output bit."""
    h ^= h >> _S33
    h *= _M1
    h ^= h >> _S33
    h *= _M2
    h ^= h >> _S33
    return h


@helper
def _table_size(n):
    size = 16
    while size < 2 * n:
        size *= 2
    return size


@kernel((U2,), cost=0.4)
def _weld_positions(bits):
    """Welded ids of rows of ``bits`` (n, k >= 3) uint64 (float64 bit patterns of the positions, -0.0
    already made +0.0, then any further key columns: the tear's labels).

    returns welded (n,) int64 in order of first appearance, representative (w,) int64 (first row)
    """
    n = bits.shape[0]
    size = _table_size(n)
    mask = np.uint64(size - 1)
    table = np.full(size, -1, np.int64)          # welded id stored at its hash slot
    welded = np.empty(n, np.int64)
    representative = np.empty(n, np.int64)
    count = 0
    for i in range(n):
        h = bits[i, 0] * _K[0] ^ bits[i, 1] * _K[1] ^ bits[i, 2] * _K[2]
        for c in range(3, bits.shape[1]):
            h = (h ^ bits[i, c]) * _K[3]
        slot = _mix(h) & mask
        while True:
            w = table[slot]
            if w < 0:
                table[slot] = count
                representative[count] = i
                welded[i] = count
                count += 1
                break
            r = representative[w]
            same = True
            for c in range(bits.shape[1]):
                same = same and bits[r, c] == bits[i, c]
            if same:
                welded[i] = w
                break
            slot = (slot + np.uint64(1)) & mask
    return welded, representative[:count].copy()


def _weld(vertices, labels):
    """(welded (n,), representative (w,)) of finite vertices, by bitwise-equal position (and label)."""
    # bitwise equality of positions, with -0.0 == 0.0 (adding +0.0 turns -0.0 into +0.0)
    positions = np.ascontiguousarray(vertices, dtype=np.float64) + 0.0
    bits = positions.view(np.uint64)
    if labels is not None and np.any(labels):
        bits = np.concatenate((bits, np.asarray(labels, np.int64).reshape(-1, 1).view(np.uint64)), axis=1)
    return _weld_positions(bits)


@helper
def _key_bits(bits, vertices, labels, v):
    """The weld key of vertex v (4 uint64 scalars: no array per key): its position's bit patterns
    (``bits``: ``vertices`` viewed as uint64; -0.0 read as +0.0) and its label."""
    zero = np.uint64(0)
    x = zero if vertices[v, 0] == 0.0 else bits[v, 0]
    y = zero if vertices[v, 1] == 0.0 else bits[v, 1]
    z = zero if vertices[v, 2] == 0.0 else bits[v, 2]
    return x, y, z, np.uint64(labels[v])


@helper
def _find(table, keys, key, mask):
    """The slot of ``key`` (4 uint64) in the open-addressed ``table`` of rows of ``keys``: where it is,
    or the empty slot where it goes."""
    x, y, z, label = key
    slot = _mix(x * _K[0] ^ y * _K[1] ^ z * _K[2] ^ label * _K[3]) & mask
    while table[slot] >= 0:
        r = table[slot]
        if keys[r, 0] == x and keys[r, 1] == y and keys[r, 2] == z and keys[r, 3] == label:
            break
        slot = (slot + np.uint64(1)) & mask
    return slot


@helper
def _boundary_of(vertices, labels, faces, rows, asked):
    """(a,) bool: whether each ``asked`` vertex lies on a boundary edge (one face) of the faces
    ``faces[rows]`` (k, 3) welded by position and label (``topology.boundary_flags`` of these faces,
    for these vertices only; they must hold the whole fan of every asked vertex). O(k + a), not
    O(vertices)."""
    k = rows.shape[0]
    bits = vertices.view(np.uint64)
    size = _table_size(3 * k)
    mask = np.uint64(size - 1)
    table = np.full(size, -1, np.int64)            # welded id at its key's slot
    keys = np.empty((3 * k, 4), np.uint64)
    corner = np.empty((k, 3), np.int64)           # the welded id of each corner
    count = 0
    for f in range(k):
        for c in range(3):
            key = _key_bits(bits, vertices, labels, faces[rows[f], c])
            slot = _find(table, keys, key, mask)
            if table[slot] < 0:
                for j in range(4):
                    keys[count, j] = key[j]
                table[slot] = count
                count += 1
            corner[f, c] = table[slot]
    # the welded edges and their face counts: a table keyed by the pair (lower, higher)
    esize = _table_size(3 * k)
    emask = np.uint64(esize - 1)
    edge_lo = np.full(esize, -1, np.int64)
    edge_hi = np.empty(esize, np.int64)
    faces_on = np.zeros(esize, np.int64)
    for f in range(k):
        for c in range(3):
            lo, hi = min(corner[f, c], corner[f, (c + 1) % 3]), max(corner[f, c], corner[f, (c + 1) % 3])
            slot = _mix(np.uint64(lo) * _K[0] ^ np.uint64(hi) * _K[1]) & emask
            while edge_lo[slot] >= 0 and not (edge_lo[slot] == lo and edge_hi[slot] == hi):
                slot = (slot + np.uint64(1)) & emask
            edge_lo[slot], edge_hi[slot] = lo, hi
            faces_on[slot] += 1
    on_boundary = np.zeros(count, np.bool_)
    for slot in range(esize):
        if edge_lo[slot] >= 0 and faces_on[slot] == 1:
            on_boundary[edge_lo[slot]] = True
            on_boundary[edge_hi[slot]] = True
    out = np.zeros(asked.shape[0], np.bool_)
    for i in range(asked.shape[0]):
        slot = _find(table, keys, _key_bits(bits, vertices, labels, asked[i]), mask)
        out[i] = table[slot] >= 0 and on_boundary[table[slot]]
    return out
