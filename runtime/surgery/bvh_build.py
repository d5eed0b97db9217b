"""Building the tree of ``bvh.TriangleBVH`` (see bvh.py for the design): top-down, each node split at
the middle of its centroids' extent along the longest axis, leaves of at most ``leaf_size``
triangles, in one numba loop with an explicit stack; and the one-leaf "tree" of a small patch."""
import numpy as np

from .._shared.jit import F2, I2, f8, i8, kernel


@kernel((F2, I2, i8, f8), cost=1.5)
def _build(positions, faces, leaf_size, padding):
    """Build the hierarchy.

    positions : (n, 3) float64 ; faces : (m, 3) int64, m >= 1
    returns the fields of ``BVHArrays``
    """
    m = faces.shape[0]
    centroid = np.empty((m, 3))
    tri_lo = np.empty((m, 3))
    tri_hi = np.empty((m, 3))
    scene_lo = np.full(3, np.inf)
    scene_hi = np.full(3, -np.inf)
    for f in range(m):
        for k in range(3):
            a = positions[faces[f, 0], k]
            b = positions[faces[f, 1], k]
            c = positions[faces[f, 2], k]
            tri_lo[f, k] = min(a, min(b, c))
            tri_hi[f, k] = max(a, max(b, c))
            centroid[f, k] = (a + b + c) / 3.0
            scene_lo[k] = min(scene_lo[k], tri_lo[f, k])
            scene_hi[k] = max(scene_hi[k], tri_hi[f, k])
    extent = 0.0
    for k in range(3):
        extent = max(extent, scene_hi[k] - scene_lo[k])
    pad = padding * max(extent, 1e-300)

    cap = 2 * m
    node_lo = np.empty((cap, 3))
    node_hi = np.empty((cap, 3))
    node_left = np.full(cap, -1, np.int64)
    node_right = np.full(cap, -1, np.int64)
    node_start = np.zeros(cap, np.int64)
    node_count = np.zeros(cap, np.int64)
    order = np.arange(m)

    stack_node = np.empty(128, np.int64)
    stack_start = np.empty(128, np.int64)
    stack_end = np.empty(128, np.int64)
    top = 0
    stack_node[0], stack_start[0], stack_end[0] = 0, 0, m
    n_nodes = 1
    lo = np.empty(3)
    hi = np.empty(3)
    clo = np.empty(3)
    chi = np.empty(3)
    while top >= 0:
        node, start, end = stack_node[top], stack_start[top], stack_end[top]
        top -= 1
        lo[:] = np.inf
        hi[:] = -np.inf
        clo[:] = np.inf
        chi[:] = -np.inf
        for i in range(start, end):
            f = order[i]
            for k in range(3):
                lo[k] = min(lo[k], tri_lo[f, k])
                hi[k] = max(hi[k], tri_hi[f, k])
                clo[k] = min(clo[k], centroid[f, k])
                chi[k] = max(chi[k], centroid[f, k])
        for k in range(3):
            node_lo[node, k] = lo[k] - pad
            node_hi[node, k] = hi[k] + pad
        count = end - start
        if count <= leaf_size:
            node_start[node], node_count[node] = start, count
            continue
        axis = 0
        for k in range(1, 3):
            if chi[k] - clo[k] > chi[axis] - clo[axis]:
                axis = k
        # partition around the middle of the centroid extent, in place
        split = 0.5 * (clo[axis] + chi[axis])
        i, j = start, end - 1
        while i <= j:
            if centroid[order[i], axis] < split:
                i += 1
            else:
                order[i], order[j] = order[j], order[i]
                j -= 1
        mid = i
        if mid == start or mid == end:
            # every centroid on one side: they coincide along the longest axis (up to rounding of the
            # middle), so any order is sorted; split the list in half
            mid = start + count // 2
        left, right = n_nodes, n_nodes + 1
        n_nodes += 2
        node_left[node], node_right[node] = left, right
        if top + 3 > stack_node.shape[0]:
            stack_node = np.concatenate((stack_node, np.empty_like(stack_node)))
            stack_start = np.concatenate((stack_start, np.empty_like(stack_start)))
            stack_end = np.concatenate((stack_end, np.empty_like(stack_end)))
        top += 1
        stack_node[top], stack_start[top], stack_end[top] = right, mid, end
        top += 1
        stack_node[top], stack_start[top], stack_end[top] = left, start, mid

    tri = np.empty((m, 9))
    for i in range(m):
        f = order[i]
        for c in range(3):
            for k in range(3):
                tri[i, 3 * c + k] = positions[faces[f, c], k]
    return (node_lo[:n_nodes].copy(), node_hi[:n_nodes].copy(), node_left[:n_nodes].copy(),
            node_right[:n_nodes].copy(), node_start[:n_nodes].copy(), node_count[:n_nodes].copy(),
            order, tri)


@kernel((F2, I2, f8), cost=0.3)
def _one_leaf(positions, faces, padding):
    """The fields of ``BVHArrays`` for a single leaf holding every face (m >= 1) in order."""
    m = faces.shape[0]
    lo = np.full((1, 3), np.inf)
    hi = np.full((1, 3), -np.inf)
    tri = np.empty((m, 9))
    for f in range(m):
        for c in range(3):
            for k in range(3):
                x = positions[faces[f, c], k]
                tri[f, 3 * c + k] = x
                lo[0, k] = min(lo[0, k], x)
                hi[0, k] = max(hi[0, k], x)
    extent = max(hi[0, 0] - lo[0, 0], max(hi[0, 1] - lo[0, 1], hi[0, 2] - lo[0, 2]))
    pad = padding * max(extent, 1e-300)
    for k in range(3):
        lo[0, k] -= pad
        hi[0, k] += pad
    return (lo, hi, np.full(1, -1, np.int64), np.full(1, -1, np.int64), np.zeros(1, np.int64),
            np.full(1, m, np.int64), np.arange(m), tri)
