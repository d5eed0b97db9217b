"""Step 6 of a cut: the per-vertex arrays of both halves (originals they keep, then the new vertices).

The arrays are made here (``recycled_empty``) and filled by the kernel: a large cut's fresh pages
cost the operating system about as much time as the cut computes, and a cut repeated after the
previous halves are dropped finds their memory mapped. The halves' rigs then hold these
arrays as they are.
"""
import numpy as np

from ..._shared.frozen import kernel_array
from ..._shared.jit import F2, I1, I2, kernel
from ..._shared.memory import recycled_empty
from ..gather import gather_rows
from ..new_vertices import interpolate_attribute


@kernel((F2, I1, I1, F2, F2, F2), (I2, I1, I1, I2, I2, I2), cost=0.3)
def _assemble(values, pos_src, neg_src, extra, pos_out, neg_out):
    """Both halves' rows of one per-vertex array: ``out[:len(src)] = values[src]``, then the rows of
    ``extra`` (the new vertices).

    values (n, c) ; pos_src (np,), neg_src (nn,) int64 ; extra (k, c) ;
    pos_out (np + k, c), neg_out (nn + k, c) of values' dtype, written
    """
    c, k = values.shape[1], extra.shape[0]
    for src, out in ((pos_src, pos_out), (neg_src, neg_out)):
        gather_rows(values, src, out)
        n = src.shape[0]
        for i in range(k):
            for j in range(c):
                out[n + i, j] = extra[i, j]


def _halves(values, pos_src, neg_src, extra, shape=None):
    """(positive, negative) arrays of rows ``values[src]`` then ``extra``, of ``values``' dtype and
    ``shape`` (the trailing dimensions; default: values' own)."""
    shape = values.shape[1:] if shape is None else shape
    halves = tuple(recycled_empty((len(src) + len(extra),) + shape, values.dtype) for src in (pos_src, neg_src))
    _assemble(values, pos_src, neg_src, extra, *(h.reshape(len(h), -1) for h in halves))
    return halves


def _split_arrays(rig, vertices, joints, weights, pos_src, neg_src, new, new_rest, new_joints, new_weights):
    """Per-vertex arrays of both halves: (vertices, joints, weights, attributes) for each.

    new : NewVertices on the crossed edges; new_rest (k, 3), new_joints (k, 4), new_weights (k, 4)
    """
    out = [_halves(vertices, pos_src, neg_src, new_rest), _halves(joints, pos_src, neg_src, new_joints),
           _halves(weights, pos_src, neg_src, new_weights)]
    attributes = ({}, {})
    for key, values in rig.attributes.items():
        values = kernel_array(np.asarray(values))         # (read-only: its writeable buffer, one kernel type)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        if flat.dtype.kind != "f":
            flat = flat.astype(np.float64)
        extra = interpolate_attribute(key, flat, new)
        for h, rows in enumerate(_halves(flat, pos_src, neg_src, extra, values.shape[1:])):
            attributes[h][key] = rows
    return [(out[0][h], out[1][h], out[2][h], attributes[h]) for h in range(2)]
