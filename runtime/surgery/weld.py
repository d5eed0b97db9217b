"""Welding: which vertices of a mesh are one, by bitwise-equal position (and, for the tear, equal
label). A hash table in one numba pass (open addressing, linear probing, at least twice the keys so
that probes stay short); welded vertices are numbered by first appearance, each represented by its
lowest vertex. ``topology.py`` builds the welded topology on it."""
import numpy as np

from .._shared.jit import U2, helper, kernel

_M1 = np.uint64(0xFF51AFD7ED558CCD)
_M2 = np.uint64(0xC4CEB9FE1A85EC53)
_S33 = np.uint64(33)
_ROT = np.uint64(0x9E3779B97F4A7C15)


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
        h = _mix(bits[i, 0] ^ _mix(bits[i, 1] + _ROT) ^ _mix(bits[i, 2] * _ROT))
        for c in range(3, bits.shape[1]):
            h = _mix(h ^ (bits[i, c] + _ROT))
        slot = h & mask
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
