"""Step 6 of a cut: the per-vertex arrays of both halves (originals they keep, then the new vertices)."""
import math

import numpy as np
from ..._shared.jit import kernel, F1, F2, I1, I2, b1


@kernel((F2, I1, I1, F1, b1), cost=0.3)
def _lerp_rows(values, lo, hi, t, unit):
    """Rows (k, c) of new vertices: (1 − t) values[lo] + t values[hi]; renormalised when ``unit``
    (normals), a zero result staying zero."""
    k = lo.shape[0]
    c = values.shape[1]
    out = np.empty((k, c))
    for i in range(k):
        s = 0.0
        for j in range(c):
            x = (1.0 - t[i]) * values[lo[i], j] + t[i] * values[hi[i], j]
            out[i, j] = x
            s += x * x
        if unit and s > 0.0:
            inv = 1.0 / math.sqrt(s)
            for j in range(c):
                out[i, j] *= inv
    return out


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


def _split_arrays(rig, vertices, joints, weights, pos_src, neg_src, new_lo, new_hi, new_t, new_rest,
                  new_joints, new_weights):
    """Per-vertex arrays of both halves: (vertices, joints, weights, attributes) for each."""
    out = [_assemble(vertices, pos_src, neg_src, new_rest), _assemble(joints, pos_src, neg_src, new_joints),
           _assemble(weights, pos_src, neg_src, new_weights)]
    attributes = ({}, {})
    for key, values in rig.attributes.items():
        values = np.asarray(values)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        if flat.dtype.kind != "f":
            flat = flat.astype(np.float64)
        if key.startswith("_"):
            # application-specific data (e.g. the tear's "_TEAR" labels) may not be interpolable:
            # a new vertex takes the row of the nearer edge end
            new = np.where((np.asarray(new_t) < 0.5)[:, None], flat[new_lo], flat[new_hi])
        else:
            unit = key == "NORMAL" and flat.shape[1] == 3
            new = _lerp_rows(flat, new_lo, new_hi, new_t, unit).astype(flat.dtype, copy=False)
        for h, rows in enumerate(_assemble(flat, pos_src, neg_src, new)):
            attributes[h][key] = rows.reshape((len(rows),) + values.shape[1:])
    return [(out[0][h], out[1][h], out[2][h], attributes[h]) for h in range(2)]
