"""Building the tree of ``bvh.TriangleBVH`` and ``dynamic_bvh.DynamicBVH`` (see bvh.py for the design):
top-down, each node split at the middle of its centroids' extent along the longest axis, leaves of at
most ``leaf_size`` triangles, in one numba loop with an explicit stack; and the one-leaf "tree" of a
small patch.

Neither copies the triangles: the trees read a triangle's corners as positions[faces[face]], and the
build keeps only the centroids (24 bytes a face, freed on return) besides the tree itself.
"""
import numpy as np
from numba import types

from .._shared.jit import F2, I2, f8, i8, kernel

#: the index arrays of the trees (node children and ranges, slot -> face): int32, which halves them
#: (face ids and slots stay below 2**31: a mesh that large would not fit in memory anyway)
N1 = types.int32[::1]


@kernel((F2, I2, N1, i8, f8, i8), cost=1.5)
def _build(positions, faces, order, leaf_size, padding, spare):
    """Build the hierarchy over the faces ``order`` (k >= 1 face ids), permuting ``order`` in place
    into leaf order.

    positions : (n, 3) float64 ; faces : (F, 3) int64, rows by face id ; order : (k,) int32 ;
    spare : node rows to allocate beyond the 2k - 1 that a tree of k faces can use at most
    returns (lo, hi, left, right, start, count, n_nodes, pad): node arrays of 2k - 1 + spare rows
    (``BVHArrays``' first six fields), of which the first n_nodes are the tree and the rest are
    allocated, not written (so not resident: a DynamicBVH grows into them); pad the box padding
    """
    k = order.shape[0]
    # centroids in slot order, permuted with ``order``: the partitions scan them sequentially
    centroid = np.empty((k, 3))
    scene_lo = np.full(3, np.inf)
    scene_hi = np.full(3, -np.inf)
    for i in range(k):
        f = order[i]
        for d in range(3):
            a = positions[faces[f, 0], d]
            b = positions[faces[f, 1], d]
            c = positions[faces[f, 2], d]
            centroid[i, d] = (a + b + c) / 3.0
            scene_lo[d] = min(scene_lo[d], min(a, min(b, c)))
            scene_hi[d] = max(scene_hi[d], max(a, max(b, c)))
    extent = 0.0
    for d in range(3):
        extent = max(extent, scene_hi[d] - scene_lo[d])
    pad = padding * max(extent, 1e-300)

    rows = 2 * k - 1 + spare
    node_lo = np.empty((rows, 3))
    node_hi = np.empty((rows, 3))
    node_left = np.empty(rows, np.int32)
    node_right = np.empty(rows, np.int32)
    node_start = np.empty(rows, np.int32)
    node_count = np.empty(rows, np.int32)

    stack_node = np.empty(128, np.int64)
    stack_start = np.empty(128, np.int64)
    stack_end = np.empty(128, np.int64)
    top = 0
    stack_node[0], stack_start[0], stack_end[0] = 0, 0, k
    n_nodes = 1
    clo = np.empty(3)
    chi = np.empty(3)
    while top >= 0:
        node, start, end = stack_node[top], stack_start[top], stack_end[top]
        top -= 1
        count = end - start
        if count <= leaf_size:
            node_left[node], node_right[node] = -1, -1
            node_start[node], node_count[node] = start, count
            continue
        clo[:] = np.inf
        chi[:] = -np.inf
        for i in range(start, end):
            for d in range(3):
                clo[d] = min(clo[d], centroid[i, d])
                chi[d] = max(chi[d], centroid[i, d])
        axis = 0
        for d in range(1, 3):
            if chi[d] - clo[d] > chi[axis] - clo[axis]:
                axis = d
        # partition around the middle of the centroid extent, in place
        split = 0.5 * (clo[axis] + chi[axis])
        i, j = start, end - 1
        while i <= j:
            if centroid[i, axis] < split:
                i += 1
            else:
                order[i], order[j] = order[j], order[i]
                for d in range(3):
                    centroid[i, d], centroid[j, d] = centroid[j, d], centroid[i, d]
                j -= 1
        mid = i
        if mid == start or mid == end:
            # every centroid on one side: they coincide along the longest axis (up to rounding of the
            # middle), so any order is sorted; split the list in half
            mid = start + count // 2
        left, right = n_nodes, n_nodes + 1
        n_nodes += 2
        node_left[node], node_right[node] = left, right
        node_start[node], node_count[node] = 0, 0
        if top + 3 > stack_node.shape[0]:
            stack_node = np.concatenate((stack_node, np.empty_like(stack_node)))
            stack_start = np.concatenate((stack_start, np.empty_like(stack_start)))
            stack_end = np.concatenate((stack_end, np.empty_like(stack_end)))
        top += 1
        stack_node[top], stack_start[top], stack_end[top] = right, mid, end
        top += 1
        stack_node[top], stack_start[top], stack_end[top] = left, start, mid

    # boxes bottom up (children come after their parent): a leaf's from its triangles, an inner node's
    # the union of its children's (min(a - pad, b - pad) == min(a, b) - pad exactly: rounding is monotone)
    for node in range(n_nodes - 1, -1, -1):
        left, right = node_left[node], node_right[node]
        if left >= 0:
            for d in range(3):
                node_lo[node, d] = min(node_lo[left, d], node_lo[right, d])
                node_hi[node, d] = max(node_hi[left, d], node_hi[right, d])
            continue
        node_lo[node] = np.inf
        node_hi[node] = -np.inf
        for i in range(node_start[node], node_start[node] + node_count[node]):
            f = order[i]
            for c in range(3):
                for d in range(3):
                    x = positions[faces[f, c], d]
                    node_lo[node, d] = min(node_lo[node, d], x)
                    node_hi[node, d] = max(node_hi[node, d], x)
        for d in range(3):
            node_lo[node, d] -= pad
            node_hi[node, d] += pad
    return node_lo, node_hi, node_left, node_right, node_start, node_count, n_nodes, pad


@kernel((F2, I2, f8), cost=0.3)
def _one_leaf(positions, faces, padding):
    """The tree fields of ``BVHArrays`` (lo, hi, left, right, start, count, order) for a single leaf
    holding every face (m >= 1) in order."""
    m = faces.shape[0]
    lo = np.full((1, 3), np.inf)
    hi = np.full((1, 3), -np.inf)
    for f in range(m):
        for c in range(3):
            for k in range(3):
                x = positions[faces[f, c], k]
                lo[0, k] = min(lo[0, k], x)
                hi[0, k] = max(hi[0, k], x)
    extent = max(hi[0, 0] - lo[0, 0], max(hi[0, 1] - lo[0, 1], hi[0, 2] - lo[0, 2]))
    pad = padding * max(extent, 1e-300)
    for k in range(3):
        lo[0, k] -= pad
        hi[0, k] += pad
    return (lo, hi, np.full(1, -1, np.int32), np.full(1, -1, np.int32), np.zeros(1, np.int32),
            np.full(1, m, np.int32), np.arange(m).astype(np.int32))
