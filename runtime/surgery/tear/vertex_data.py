"""Step 7 of a tear stroke: the vertex arrays of the torn mesh (new vertices, twins, labels,
opening, rest placement in a pose)."""
import numpy as np

from ..._shared.jit import helper
from ...algebra.vec3 import _copy_row, _set_row
from ..new_vertices import _blended, _solve_linear, _to_rest, blend_weight_rows
from .records import MOVED_NODE, MOVED_RANK, MOVED_SIDE, MOVED_VERTEX, POINT, TWIN_NODE, TWIN_OF, TWIN_RANK


@helper
def _vertex_data(rows, n, top, path_float, pieces, slit, opening, affines, posed):
    """Step 7 and the vertex arrays of the torn mesh: originals, new vertices, twins.

    New vertices get interpolated weights (``_blend_weights``) and, at rest, their path point as
    position; in a pose, one rest position per path node, solved with the node's first copy's
    weights, so that all copies of a node (one per attribute-split copy of a seam edge) keep one
    position and stay welded even where their weights differ a little. Twins copy their vertex. The
    far side of the slit gets the new tear label (``top + 1`` + rank, ``top`` the highest label of the
    whole mesh, which the n rows here may be only a part of). ``opening`` is (width, normal (3,),
    offsets (k, 2)): with a width > 0 the near side of each split node moves along ``normal`` by
    ``offsets[j, 0]`` and the far side against it by ``offsets[j, 1]`` (``opening._opening_offsets``:
    they sum to the width; half of it each where no face around the path loses too much of its area):
    in a pose, the offset goes through the inverse blended linear part of the node's first copy on
    that side (again one offset per node and side, for the same reason).

    rows : the vertex arrays of the torn mesh, (vertices (N, 3) float64, joints (N, 4) int64, weights
        (N, 4) float64, labels (N,) int64) with N = n + v + t, the originals in their first n rows (the
        caller copies them: numpy's copy beats a compiled loop); filled here
    path_float : (k, 4) Path.points ; pieces : Pieces, slit : Slit (as tuples) ; affines (B, 12), posed
    returns the largest placement residual |skinned new vertex - its posed path point| (0 at rest)
    """
    out_v, out_j, out_w, out_l = rows
    width, normal, offsets = opening
    affected, tris, new_node, new_src, new_coef, _ = pieces
    split, twins, moved, side_a, side_b = slit
    v, t = new_node.shape[0], twins.shape[0]
    new_joints, new_weights = blend_weight_rows(new_src, new_coef, out_j, out_w)
    k_nodes = path_float.shape[0]
    first = np.full(k_nodes, -1, np.int64)
    residual = 0.0
    for i in range(v):
        _copy_row(out_j, n + i, new_joints, i)
        _copy_row(out_w, n + i, new_weights, i)
        out_l[n + i] = max(out_l[new_src[i, 0]], max(out_l[new_src[i, 1]], out_l[new_src[i, 2]]))
        j = new_node[i]
        if not posed:
            for c in range(3):
                out_v[n + i, c] = path_float[j, POINT + c]
        elif first[j] >= 0:
            _copy_row(out_v, n + i, out_v, n + first[j])
        else:
            first[j] = i
            guess = np.empty(3)
            for c in range(3):
                guess[c] = (new_coef[i, 0] * out_v[new_src[i, 0], c] + new_coef[i, 1] * out_v[new_src[i, 1], c]
                            + new_coef[i, 2] * out_v[new_src[i, 2], c])
            blend = _blended(new_joints, new_weights, affines, i)
            x, res = _to_rest(path_float[j, POINT:POINT + 3], guess, blend)
            _set_row(out_v, n + i, x)
            if not res <= residual:          # NaN too: a residual that is not a number is reported
                residual = res
    for i in range(t):
        _copy_row(out_v, n + v + i, out_v, twins[i, TWIN_OF])
        _copy_row(out_j, n + v + i, out_j, twins[i, TWIN_OF])
        _copy_row(out_w, n + v + i, out_w, twins[i, TWIN_OF])
        out_l[n + v + i] = top + 1 + twins[i, TWIN_RANK]
    for i in range(moved.shape[0]):
        if moved[i, MOVED_SIDE] < 0:
            out_l[moved[i, MOVED_VERTEX]] = top + 1 + moved[i, MOVED_RANK]
    if width > 0.0:
        # (vertex, sign, node) of every vertex of a split node; offsets per (node, side)
        k = moved.shape[0] + t
        ids = np.empty(k, np.int64)
        signs = np.empty(k)
        nodes = np.empty(k, np.int64)
        for i in range(moved.shape[0]):
            ids[i], signs[i], nodes[i] = moved[i, MOVED_VERTEX], moved[i, MOVED_SIDE], moved[i, MOVED_NODE]
        for i in range(t):
            q = moved.shape[0] + i
            ids[q], signs[q], nodes[q] = n + v + i, -1.0, twins[i, TWIN_NODE]
        offset = np.empty((k_nodes, 2, 3))
        done = np.zeros((k_nodes, 2), np.bool_)
        delta = np.empty(3)
        for i in range(k):
            side = 0 if signs[i] > 0 else 1
            j = nodes[i]
            if not done[j, side]:
                done[j, side] = True
                share = offsets[j, side]
                for c in range(3):
                    delta[c] = signs[i] * (share * normal[c])
                if posed:
                    delta = _solve_linear(_blended(out_j, out_w, affines, ids[i]), delta)
                for c in range(3):
                    offset[j, side, c] = delta[c]
        for i in range(k):
            for c in range(3):
                out_v[ids[i], c] += offset[nodes[i], 0 if signs[i] > 0 else 1, c]
    return residual
