"""Step 6 of a cut: the per-vertex arrays of both halves (originals they keep, then the new vertices)."""
import numpy as np

from ..._shared.frozen import kernel_array
from ..._shared.jit import F2, I1, I2, kernel
from ..new_vertices import interpolate_attribute


@kernel((F2, I1, I1, F2), (I2, I1, I1, I2), cost=0.3)
def _assemble(values, pos_src, neg_src, extra):
    """Both halves' rows of one per-vertex array: values[src] followed by ``extra`` (the new vertices)."""
    c = values.shape[1]
    k = extra.shape[0]
    halves = []
    for src in (pos_src, neg_src):
        n = src.shape[0]
        out = np.empty((n + k, c), values.dtype)
        for i in range(n):
            for j in range(c):
                out[i, j] = values[src[i], j]
        for i in range(k):
            for j in range(c):
                out[n + i, j] = extra[i, j]
        halves.append(out)
    return halves[0], halves[1]


def _split_arrays(rig, vertices, joints, weights, pos_src, neg_src, new, new_rest, new_joints, new_weights):
    """Per-vertex arrays of both halves: (vertices, joints, weights, attributes) for each.

    new : NewVertices on the crossed edges; new_rest (k, 3), new_joints (k, 4), new_weights (k, 4)
    """
    out = [_assemble(vertices, pos_src, neg_src, new_rest), _assemble(joints, pos_src, neg_src, new_joints),
           _assemble(weights, pos_src, neg_src, new_weights)]
    attributes = ({}, {})
    for key, values in rig.attributes.items():
        values = kernel_array(np.asarray(values))         # (read-only: its writeable buffer, one kernel type)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        if flat.dtype.kind != "f":
            flat = flat.astype(np.float64)
        extra = interpolate_attribute(key, flat, new)
        for h, rows in enumerate(_assemble(flat, pos_src, neg_src, extra)):
            attributes[h][key] = rows.reshape((len(rows),) + values.shape[1:])
    return [(out[0][h], out[1][h], out[2][h], attributes[h]) for h in range(2)]
