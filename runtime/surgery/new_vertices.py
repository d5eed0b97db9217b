"""Blending skin weight rows: the weights of vertices created on edges (cut, tear) and inside faces
(tear), kept in the layout every rig has: 4 influences, largest first, summing to 1."""
import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def blend_weight_rows(src, coef, joints, weights):
    """Weights of interpolated vertices: Σ_r coef[i, r] · (row src[i, r]) over the union of the rows'
    bones, the 4 largest kept and renormalised, sorted by decreasing weight; unused slots bone 0 with
    weight 0 (the layout ``validate.check_mesh`` produces). Edge points blend 2 rows (1 − t, t),
    points inside faces 3 (barycentric).

    src : (k, r) int64 ; coef : (k, r) float64 ; joints, weights : (n, 4)
    returns joints (k, 4) int64, weights (k, 4) float64
    """
    k = src.shape[0]
    out_j = np.zeros((k, 4), np.int64)
    out_w = np.zeros((k, 4))
    bones = np.empty(4 * src.shape[1], np.int64)
    values = np.empty(4 * src.shape[1])
    for i in range(k):
        count = 0
        for r in range(src.shape[1]):
            v = src[i, r]
            for s in range(4):
                w = coef[i, r] * weights[v, s]
                if w <= 0.0:
                    continue
                found = False
                for q in range(count):
                    if bones[q] == joints[v, s]:
                        values[q] += w
                        found = True
                        break
                if not found:
                    bones[count] = joints[v, s]
                    values[count] = w
                    count += 1
        kept = min(4, count)
        total = 0.0
        for slot in range(kept):            # selection of the largest (ties: the bone met first)
            best = slot
            for q in range(slot + 1, count):
                if values[q] > values[best]:
                    best = q
            bones[slot], bones[best] = bones[best], bones[slot]
            values[slot], values[best] = values[best], values[slot]
            total += values[slot]
        for slot in range(kept):
            out_j[i, slot] = bones[slot]
            out_w[i, slot] = values[slot] / total
    return out_j, out_w
