"""Step 6 of a tear stroke: the torn face list, and the far side's own copies of the path vertices
(the slit opens)."""
import numpy as np

from ..._shared.jit import F1, F2, I1, I2, helper, kernel
from ...generated.kernels import point_plane_distance
from ..surface import WELDED_MESH
from .records import ID, KIND, POINT, VERTEX


@helper
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@helper
def _linked(wf, fa, ka, fb, kb, before, after):
    """Whether faces fa and fb (node at corners ka, kb) share an edge from the node that is not a
    path edge (to the previous node ``before`` or the next ``after``; -1 when there is none)."""
    for i in range(1, 3):
        x = wf[fa, (ka + i) % 3]
        if x == before or x == after:
            continue
        if x == wf[fb, (kb + 1) % 3] or x == wf[fb, (kb + 2) % 3]:
            return True
    return False


@helper
def _append_row(rows, count, a, b, c, d):
    """rows[count, :4] = (a, b, c, d) (columns beyond the array's width dropped), growing the
    array when full; returns (rows, count + 1)."""
    if count == rows.shape[0]:
        rows = np.concatenate((rows, np.empty_like(rows)))
    rows[count, 0], rows[count, 1], rows[count, 2], rows[count, 3] = a, b, c, d
    return rows, count + 1


@kernel((I2, I2, I1, F2, F2, F1, I1), cost=2.9)
def _open_slit(faces, wf, node_w, positions, new_positions, plane, candidates):
    """Give the faces on the far side of the path their own copies of the path's vertices.

    faces : (m, 3) int64 torn faces, modified in place
    wf : (m, 3) int64 their welded corners; path node j is welded vertex node_w[j]
    node_w : (k,) int64
    positions : (n, 3), new_positions (v, 3) float64 surface positions of the vertices ``faces`` use
        (vertex i >= n is new vertex i - n)
    plane : (4,) the tear plane
    candidates : (c,) int64 sorted rows of ``faces`` that may touch a path node (the others are skipped)

    Around each path node, the faces that touch it fall into groups joined by edges from the node
    that are not path edges: two groups at a node inside the path (one per side), one at an end that
    lies inside the surface (it stays single: the slit's end), two at an end on an existing boundary.
    The groups of all split nodes, joined the same way, form the two sides of the slit (two per piece
    of a path that jumps across an existing slit); at each node the side whose faces lie furthest
    along the plane normal (summed signed distances of their centroids) keeps the original vertices,
    the other gets copies ("twins"), one per attribute-split copy it uses. A
    copy used only by far-side faces is moved to that side instead of being twinned.

    returns split (k,) bool; twins (t, 3) int64 rows (vertex it copies, far side rank: 0 for the usual
        single far side, path node), twin i being vertex n + v + i; moved (s, 4) int64 rows (existing
        vertex that belongs to a side, +1 near side / -1 far side, far side rank or -1, path node);
        side_a, side_b (k,) int64 one vertex per node on each side
    """
    m = faces.shape[0]
    k_nodes = node_w.shape[0]
    n = positions.shape[0]
    n_vertices = n + new_positions.shape[0]
    top = 0
    for j in range(k_nodes):
        top = max(top, node_w[j])
    for f in candidates:
        for c in range(3):
            top = max(top, wf[f, c])
    node_of = np.full(top + 1, -1, np.int64)
    for j in range(k_nodes):
        node_of[node_w[j]] = j
    # the corners (face, corner) at each node, grouped by node
    offsets = np.zeros(k_nodes + 1, np.int64)
    for f in candidates:
        for c in range(3):
            j = node_of[wf[f, c]]
            if j >= 0:
                offsets[j + 1] += 1
    for j in range(k_nodes):
        offsets[j + 1] += offsets[j]
    fill = offsets[:-1].copy()
    ent_face = np.empty(offsets[-1], np.int64)
    ent_corner = np.empty(offsets[-1], np.int64)
    for f in candidates:
        for c in range(3):
            j = node_of[wf[f, c]]
            if j >= 0:
                ent_face[fill[j]], ent_corner[fill[j]] = f, c
                fill[j] += 1

    # groups around each node
    split = np.zeros(k_nodes, np.bool_)
    for j in range(k_nodes):
        s, e = offsets[j], offsets[j + 1]
        before = node_w[j - 1] if j > 0 else -1
        after = node_w[j + 1] if j + 1 < k_nodes else -1
        par = np.arange(e - s)
        for a in range(s, e):
            for b in range(a + 1, e):
                if _linked(wf, ent_face[a], ent_corner[a], ent_face[b], ent_corner[b], before, after):
                    par[_find(par, a - s)] = _find(par, b - s)
        roots = 0
        for a in range(e - s):
            if par[a] == a:
                roots += 1
        split[j] = roots >= 2

    # the sides: the same groups, joined across all split nodes
    compact = np.full(m, -1, np.int64)
    n_comp = 0
    for j in range(k_nodes):
        if split[j]:
            for a in range(offsets[j], offsets[j + 1]):
                if compact[ent_face[a]] < 0:
                    compact[ent_face[a]] = n_comp
                    n_comp += 1
    gpar = np.arange(n_comp)
    for j in range(k_nodes):
        if not split[j]:
            continue
        before = node_w[j - 1] if j > 0 else -1
        after = node_w[j + 1] if j + 1 < k_nodes else -1
        for a in range(offsets[j], offsets[j + 1]):
            for b in range(a + 1, offsets[j + 1]):
                if _linked(wf, ent_face[a], ent_corner[a], ent_face[b], ent_corner[b], before, after):
                    gpar[_find(gpar, compact[ent_face[a]])] = _find(gpar, compact[ent_face[b]])
    score = np.zeros(n_comp)
    centroid = np.empty(3)
    for f in candidates:
        if compact[f] >= 0:
            centroid[:] = 0.0
            for q in range(3):
                v = faces[f, q]
                p = positions[v] if v < n else new_positions[v - n]
                for c in range(3):
                    centroid[c] += p[c] / 3.0
            score[_find(gpar, compact[f])] += point_plane_distance(plane, centroid)
    rank = np.full(n_comp, -1, np.int64)
    n_rank = 0

    side_a = np.empty(k_nodes, np.int64)
    side_b = np.empty(k_nodes, np.int64)
    # twins and moved vertices: (vertex, side rank, path node) and (vertex, sign, side rank, node)
    twins = np.empty((16, 4), np.int64)
    n_twin = np.int64(0)
    moved = np.empty((16, 4), np.int64)
    n_moved = np.int64(0)
    for j in range(k_nodes):
        s, e = offsets[j], offsets[j + 1]
        side_a[j] = faces[ent_face[s], ent_corner[s]] if e > s else -1
        side_b[j] = side_a[j]
        if not split[j]:
            continue
        # the keeper: of the sides at this node, the one furthest along the normal (per node, as a
        # path that jumps across an existing slit has two sides for each of its pieces)
        root = np.empty(e - s, np.int64)
        keeper = -1
        for a in range(s, e):
            root[a - s] = _find(gpar, compact[ent_face[a]])
            if keeper < 0 or score[root[a - s]] > score[keeper]:
                keeper = root[a - s]
        done = np.zeros(e - s, np.bool_)      # corners already handled (same vertex, same side)
        for a in range(s, e):
            if done[a - s]:
                continue
            v = faces[ent_face[a], ent_corner[a]]
            has_keeper = False
            for b in range(s, e):
                if faces[ent_face[b], ent_corner[b]] == v and root[b - s] == keeper:
                    has_keeper = True
            # every side that uses v: the keeper's keeps v, the first other one too when the keeper
            # does not use v, the rest get twins
            v_taken = False
            if has_keeper:
                v_taken = True
                side_a[j] = v
                moved, n_moved = _append_row(moved, n_moved, v, np.int64(1), np.int64(-1), j)
            for b in range(s, e):
                if done[b - s] or faces[ent_face[b], ent_corner[b]] != v:
                    continue
                r = root[b - s]
                if r == keeper:
                    done[b - s] = True
                    continue
                if rank[r] < 0:
                    rank[r] = n_rank
                    n_rank += 1
                if not v_taken:
                    v_taken = True
                    new_v = v
                    moved, n_moved = _append_row(moved, n_moved, v, np.int64(-1), rank[r], j)
                else:
                    new_v = n_vertices + n_twin
                    twins, n_twin = _append_row(twins, n_twin, v, rank[r], j, np.int64(0))
                side_b[j] = new_v
                # every corner of v on this side takes the same vertex
                for c in range(b, e):
                    if not done[c - s] and faces[ent_face[c], ent_corner[c]] == v and root[c - s] == r:
                        done[c - s] = True
                        faces[ent_face[c], ent_corner[c]] = new_v
    return split, twins[:n_twin, :3].copy(), moved[:n_moved].copy(), side_a, side_b


@kernel((I2, F2, I2, I1, WELDED_MESH, I1, I2, I1), cost=1.0)
def _torn_faces(path_int, path_float, faces, welded, mesh, affected, tris, new_node):
    """The faces of the torn mesh, with what ``_open_slit`` needs.

    path_int, path_float : the fields of ``Path`` ; faces : (m, 3) int64 ; welded : (n,) int64 welded
    vertex of each vertex ; mesh : WeldedMesh (as a tuple) ; affected, tris, new_node : from ``Pieces``
    returns the fields of ``TornFaces``
    """
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    n_welded = wpos.shape[0]
    n, m = welded.shape[0], faces.shape[0]
    index = np.zeros(m, np.int64)              # row of each kept face in the torn faces, -1 if removed
    for f in affected:
        index[f] = -1
    m_out = m - affected.shape[0] + tris.shape[0]
    torn = np.empty((m_out, 3), np.int64)
    torn_w = np.empty((m_out, 3), np.int64)
    r = 0
    for f in range(m):
        if index[f] == 0:
            torn[r, 0], torn[r, 1], torn[r, 2] = faces[f, 0], faces[f, 1], faces[f, 2]
            torn_w[r, 0], torn_w[r, 1], torn_w[r, 2] = wfaces[f, 0], wfaces[f, 1], wfaces[f, 2]
            index[f] = r
            r += 1
    first_piece = r
    for i in range(tris.shape[0]):
        for c in range(3):
            v = tris[i, c]
            torn[r, c] = v
            torn_w[r, c] = welded[v] if v < n else n_welded + new_node[v - n]
        r += 1
    k_nodes = path_int.shape[0]
    node_w = np.empty(k_nodes, np.int64)
    for j in range(k_nodes):
        node_w[j] = path_int[j, ID] if path_int[j, KIND] == VERTEX else n_welded + j
    new_positions = np.empty((new_node.shape[0], 3))
    for i in range(new_node.shape[0]):
        for c in range(3):
            new_positions[i, c] = path_float[new_node[i], POINT + c]
    # the faces that can touch a path node, in increasing order: the kept faces around path vertices,
    # and the pieces (the last rows)
    is_candidate = np.zeros(m_out, np.bool_)
    for j in range(k_nodes):
        if path_int[j, KIND] == VERTEX:
            w = path_int[j, ID]
            for q in range(vf_offsets[w], vf_offsets[w + 1]):
                if index[vf_faces[q]] >= 0:
                    is_candidate[index[vf_faces[q]]] = True
    n_cand = m_out - first_piece
    for i in range(first_piece):
        n_cand += is_candidate[i]
    candidates = np.empty(n_cand, np.int64)
    c = 0
    for i in range(m_out):
        if i >= first_piece or is_candidate[i]:
            candidates[c] = i
            c += 1
    return torn, torn_w, node_w, new_positions, candidates
