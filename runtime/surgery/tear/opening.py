"""Step 6c of a tear stroke: how far each side of the opened slit moves (``vertex_data`` moves it).

The two sides of a split path node move apart by ``opening`` along the tear plane's normal n: the
near side by a along +n, the far side by b along -n, a + b = opening. Half each is the aim; but a side
that lies closer to a vertex or an edge of the mesh than opening/2 (a slit along a crease, or
through a vertex's neighbourhood) would move onto it, and the faces between would lose all their area
or turn over. So each node's share b is chosen so that no face around the path loses more than
``OPENING_SHARE`` of its area, as close to opening/2 as that allows.

The constraints are linear: a face whose corners x_i move by s_i n (s_i = a or -b of the corner's
node and side, 0 for a corner that does not move) has the area vector
A0 + sum_i s_i n x (x_(i+1) - x_(i+2)) exactly (a product of two moves holds n x n = 0), so its area
along A0 is |A0|^2 + sum_i s_i h_i, h_i = (n x (x_(i+1) - x_(i+2))) . A0. Written in the far shares b
(a = opening - b), keeping (1 - OPENING_SHARE) |A0|^2 of it is one half-space
sum_i h_i b_i <= OPENING_SHARE |A0|^2 + opening sum_(near corners) h_i, and 0 <= b <= opening a box:
the shares are found by cyclic projection onto the violated ones from b = opening/2 (untouched when
nothing is violated: the usual case), a bounded number of sweeps. Where no shares satisfy them all (a
node with too little room on both sides) the sides are still ``opening`` apart.
"""
import numpy as np

from ..._shared.jit import helper
from .records import MOVED_NODE, MOVED_SIDE, MOVED_VERTEX, TWIN_NODE, TWIN_OF

#: an opening moves a side of the slit at most until a face around it has lost this share of its area
OPENING_SHARE = 0.5
#: sweeps of projections onto the violated constraints before the shares are taken as they are
SWEEPS = 200


@helper
def _opening_offsets(faces, candidates, positions, new_positions, plane, slit, opening):
    """(k, 2) float64: how far the near side of each path node moves along the tear plane's normal
    (column 0) and its far side against it (column 1); opening/2 each where that takes no face around
    the path past ``OPENING_SHARE`` of its area, else the shares that keep them all (module docstring).
    Unsplit nodes: opening/2 (nothing of theirs moves).

    faces (m, 3) the torn faces after ``slit._open_slit`` (the far side's corners are its copies),
    candidates (c,) the rows of them that may touch a path node, positions (n, 3), new_positions (v, 3)
    the surface torn (posed in a posed tear: the opening is along the posed plane's normal), plane (4,),
    slit the fields of ``Slit``, opening >= 0
    """
    k_nodes = slit[0].shape[0]
    far = np.full(k_nodes, 0.5 * opening)
    if opening > 0.0:
        nodes, rates, bounds = _constraints(faces, candidates, positions, new_positions, plane, slit, opening)
        _project(far, nodes, rates, bounds, opening)
    out = np.empty((k_nodes, 2))
    for j in range(k_nodes):
        out[j, 0], out[j, 1] = opening - far[j], far[j]
    return out


@helper
def _constraints(faces, candidates, positions, new_positions, plane, slit, opening):
    """The half-spaces sum_q rates[r, q] b[nodes[r, q]] <= bounds[r] of the faces that have a moving
    corner (``nodes`` -1 where a corner does not move), one row per such face."""
    _, twins, moved, _, _ = slit
    n, v, t = positions.shape[0], new_positions.shape[0], twins.shape[0]
    # the side (+1 near, -1 far, 0 fixed) and path node of every vertex a face may use, and the vertex
    # whose position it has (a twin: the vertex it copies)
    sign = np.zeros(n + v + t, np.int64)
    node = np.zeros(n + v + t, np.int64)
    source = np.arange(n + v + t)
    for i in range(moved.shape[0]):
        sign[moved[i, MOVED_VERTEX]], node[moved[i, MOVED_VERTEX]] = moved[i, MOVED_SIDE], moved[i, MOVED_NODE]
    for i in range(t):
        sign[n + v + i], node[n + v + i], source[n + v + i] = -1, twins[i, TWIN_NODE], twins[i, TWIN_OF]
    nodes = np.full((candidates.shape[0], 3), -1, np.int64)
    rates = np.zeros((candidates.shape[0], 3))
    bounds = np.empty(candidates.shape[0])
    x = np.empty((3, 3))
    count = np.int64(0)
    for f in candidates:
        if sign[faces[f, 0]] == 0 and sign[faces[f, 1]] == 0 and sign[faces[f, 2]] == 0:
            continue
        for q in range(3):
            u = source[faces[f, q]]
            for c in range(3):
                x[q, c] = positions[u, c] if u < n else new_positions[u - n, c]
        a0 = _area_vector(x)
        area2 = a0[0] * a0[0] + a0[1] * a0[1] + a0[2] * a0[2]
        if not area2 > 0.0:
            continue                 # a face of zero area already (the file's): nothing to keep
        bound = OPENING_SHARE * area2
        for q in range(3):
            s = sign[faces[f, q]]
            if s != 0:
                h = _area_rate(x, q, plane, a0)
                nodes[count, q], rates[count, q] = node[faces[f, q]], h
                if s > 0:
                    bound += opening * h
        bounds[count] = bound
        count += 1
    return nodes[:count], rates[:count], bounds[:count]


@helper
def _project(far, nodes, rates, bounds, opening):
    """Cyclic projection of the far shares ``far`` (k,) onto the violated half-spaces (``_constraints``)
    and the box [0, opening], in place, until none is violated or ``SWEEPS`` sweeps."""
    for _ in range(SWEEPS):
        violated = False
        for r in range(nodes.shape[0]):
            lhs, norm2 = 0.0, 0.0
            for q in range(3):
                if nodes[r, q] >= 0:
                    lhs += rates[r, q] * far[nodes[r, q]]
                    norm2 += rates[r, q] * rates[r, q]
            excess = lhs - bounds[r]
            if not (excess > 1e-12 * abs(bounds[r]) and norm2 > 0.0):
                continue
            violated = True
            step = excess / norm2
            for q in range(3):
                j = nodes[r, q]
                if j >= 0:
                    far[j] = min(max(far[j] - step * rates[r, q], 0.0), opening)
        if not violated:
            return


@helper
def _area_vector(x):
    """(x1 - x0) x (x2 - x0) of the corners x (3, 3)."""
    out = np.empty(3)
    u0, u1, u2 = x[1, 0] - x[0, 0], x[1, 1] - x[0, 1], x[1, 2] - x[0, 2]
    w0, w1, w2 = x[2, 0] - x[0, 0], x[2, 1] - x[0, 1], x[2, 2] - x[0, 2]
    out[0], out[1], out[2] = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
    return out


@helper
def _area_rate(x, q, n, a0):
    """h_q = (n x (x_(q+1) - x_(q+2))) . a0: how fast the area along a0 grows as corner q of x (3, 3)
    moves along n (the first three entries of ``n``)."""
    d0 = x[(q + 1) % 3, 0] - x[(q + 2) % 3, 0]
    d1 = x[(q + 1) % 3, 1] - x[(q + 2) % 3, 1]
    d2 = x[(q + 1) % 3, 2] - x[(q + 2) % 3, 2]
    return ((n[1] * d2 - n[2] * d1) * a0[0] + (n[2] * d0 - n[0] * d2) * a0[1]
            + (n[0] * d1 - n[1] * d0) * a0[2])
