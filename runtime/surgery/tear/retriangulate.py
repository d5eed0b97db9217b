"""Step 5 of a tear stroke: split the crossed faces so that the path is a chain of mesh edges, and
create the new vertices (edge crossings and points inside faces)."""
import math

import numpy as np

from ..._shared.jit import F2, I2, f8, helper, i8, kernel
from ...generated.kernels import barycentric
from ..surface import WELDED_MESH
from .face_split import _triangulate_face
from .records import CARRIER, CARRIER_KIND, EDGE, EDGE_T, FACE, FACE_CARRIER, ID, KIND, POINT, VERTEX


@helper
def _append(values, count, value, slot):
    """Append ``value`` (a face) to ``values[:count]`` and record where (``slot``); grows the array."""
    if count == values.shape[0]:
        values = np.concatenate((values, np.empty_like(values)))
    values[count] = value
    slot[value] = count
    return values, count + 1


@helper
def _face_nodes(path_int, slot, n_aff, ef_offsets, ef_faces, vf_offsets, vf_faces):
    """For each affected face (``slot`` maps a face to its index, -1 for the others), the path nodes
    that can concern it, increasing: a node inside it or with it as carrier, a crossing of one of its
    edges, a path vertex at one of its corners. CSR (offsets (a + 1,), nodes)."""
    k_nodes = path_int.shape[0]
    offsets = np.zeros(n_aff + 1, np.int64)
    last = np.full(n_aff, -1, np.int64)            # the last node counted for each face (no repeats)
    nodes = np.empty(0, np.int64)
    for fill in range(2):
        if fill == 1:
            for a in range(n_aff):
                offsets[a + 1] += offsets[a]
            nodes = np.empty(offsets[n_aff], np.int64)
            count = offsets[:n_aff].copy()
            last[:] = -1
        for j in range(k_nodes):
            kind, ident = path_int[j, KIND], path_int[j, ID]
            lo, hi, faces = np.int64(0), np.int64(0), ef_faces
            if kind == EDGE:
                lo, hi = ef_offsets[ident], ef_offsets[ident + 1]
            elif kind == VERTEX:
                lo, hi, faces = vf_offsets[ident], vf_offsets[ident + 1], vf_faces
            for r in range(lo - 2, hi):
                if r == lo - 2:
                    g = path_int[j, CARRIER] if path_int[j, CARRIER_KIND] == FACE_CARRIER else -1
                elif r == lo - 1:
                    g = ident if kind == FACE else -1
                else:
                    g = faces[r]
                if g < 0 or slot[g] < 0 or last[slot[g]] == j:
                    continue
                a = slot[g]
                last[a] = j
                if fill == 0:
                    offsets[a + 1] += 1
                else:
                    nodes[count[a]] = j
                    count[a] += 1
    return offsets, nodes


@helper
def _segment_coordinates(a, b, c, p):
    """Coordinates (λa, λb, λc) of p on the longest side of a triangle of zero area (its nearest
    point there; all weight on a when the three corners coincide)."""
    corners = (a, b, c)
    coords = np.zeros(3)
    coords[0] = 1.0
    longest = 0.0
    for k in range(3):
        u, v = corners[k], corners[(k + 1) % 3]
        length2 = (v[0] - u[0]) ** 2 + (v[1] - u[1]) ** 2 + (v[2] - u[2]) ** 2
        if length2 > longest:
            longest = length2
            t = ((p[0] - u[0]) * (v[0] - u[0]) + (p[1] - u[1]) * (v[1] - u[1])
                 + (p[2] - u[2]) * (v[2] - u[2])) / length2
            t = min(max(t, 0.0), 1.0)
            coords[:] = 0.0
            coords[k], coords[(k + 1) % 3] = 1.0 - t, t
    return coords[0], coords[1], coords[2]


@helper
def _new_vertex(code, f, path, faces, welded, table, n_new):
    """The new vertex of path node ``code`` as face ``f`` (of ``faces``) uses it: found among the first
    ``n_new`` of ``table`` (new_node, new_src, new_coef, head, chain: the node's new vertices are chained
    from ``head[code]`` through ``chain``) or appended there. An edge crossing has one per
    attribute-split copy of its edge (the pair of vertex ids
    of the face's corners there), with coefficients (1 - s, s) by the edge parameter from the face's
    own corner; a point inside the face has one, with its barycentric coordinates (generated
    kernel). ``path``, ``welded`` as ``_triangulate_face`` takes them.
    returns (index among the new vertices, new count)."""
    path_int, path_float = path
    wpos, wfaces, face_edges, edges = welded
    new_node, new_src, new_coef, head, chain = table
    if path_int[code, KIND] == EDGE:
        e = path_int[code, ID]
        k = 0
        while face_edges[f, k] != e:
            k += 1
        va, vb = faces[f, k], faces[f, (k + 1) % 3]
        q = head[code]
        while q >= 0:
            if (new_src[q, 0] == va and new_src[q, 1] == vb) or (new_src[q, 0] == vb and new_src[q, 1] == va):
                return q, n_new
            q = chain[q]
        s = path_float[code, EDGE_T] if wfaces[f, k] == edges[e, 0] else 1.0 - path_float[code, EDGE_T]
        new_src[n_new, 0], new_src[n_new, 1], new_src[n_new, 2] = va, vb, va
        new_coef[n_new, 0], new_coef[n_new, 1], new_coef[n_new, 2] = 1.0 - s, s, 0.0
    else:
        if head[code] >= 0:
            return head[code], n_new
        la, lb, lc = barycentric(wpos[wfaces[f, 0]], wpos[wfaces[f, 1]], wpos[wfaces[f, 2]],
                                 path_float[code, POINT:POINT + 3])
        if not (math.isfinite(la) and math.isfinite(lb) and math.isfinite(lc)):
            # a face of zero area (the file's, or a sliver): its longest side is all there is of it
            la, lb, lc = _segment_coordinates(wpos[wfaces[f, 0]], wpos[wfaces[f, 1]], wpos[wfaces[f, 2]],
                                              path_float[code, POINT:POINT + 3])
        # a point on the face's boundary may come out a rounding error outside
        la, lb, lc = max(la, 0.0), max(lb, 0.0), max(lc, 0.0)
        total = la + lb + lc
        new_src[n_new, 0], new_src[n_new, 1], new_src[n_new, 2] = faces[f, 0], faces[f, 1], faces[f, 2]
        new_coef[n_new, 0], new_coef[n_new, 1], new_coef[n_new, 2] = la / total, lb / total, lc / total
    new_node[n_new] = code
    chain[n_new] = head[code]
    head[code] = n_new
    return n_new, n_new + 1


@kernel((I2, F2, I2, WELDED_MESH, i8, f8), cost=8.0)
def _retriangulate(path_int, path_float, faces, mesh, n_vertices, on_edge):
    """Split every face the path crosses (and every face on a crossed edge) and create the new vertices.

    path_int, path_float : the fields of ``Path`` ; faces : (m, 3) int64 ; mesh : WeldedMesh (as a tuple)
    n_vertices : int, the torn mesh's new vertices count from it ; on_edge : tolerance (``tol.on_edge``)
    returns the fields of ``Pieces``:
        affected (a,) int64 faces replaced by their pieces
        tris (q, 3) int64 the pieces, as vertex ids of the torn mesh (new vertices from ``n_vertices``)
        new_node (v,) int64 path node of each new vertex
        new_src (v, 3) int64, new_coef (v, 3) float64: each new vertex interpolates the data of the
            vertices new_src with coefficients new_coef (``_new_vertex``)
        parent (q,) int64 the index in ``affected`` of the face each piece is a piece of
    """
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    k_nodes = path_int.shape[0]
    slot = np.full(faces.shape[0], -1, np.int64)     # index of each affected face in ``affected``
    affected = np.empty(4 * k_nodes + 8, np.int64)
    n_aff = np.int64(0)
    for j in range(k_nodes):
        for r in range(3):
            if r == 0:
                g = path_int[j, CARRIER] if path_int[j, CARRIER_KIND] == FACE_CARRIER else -1
            elif r == 1:
                g = path_int[j, ID] if path_int[j, KIND] == FACE else -1
            else:
                g = -1
            if g >= 0 and slot[g] < 0:
                affected, n_aff = _append(affected, n_aff, g, slot)
        if path_int[j, KIND] == EDGE:
            e = path_int[j, ID]
            for r in range(ef_offsets[e], ef_offsets[e + 1]):
                if slot[ef_faces[r]] < 0:
                    affected, n_aff = _append(affected, n_aff, ef_faces[r], slot)
    affected = affected[:n_aff]
    node_offsets, node_list = _face_nodes(path_int, slot, n_aff, ef_offsets, ef_faces, vf_offsets, vf_faces)

    # (a face's pieces are at most its own nodes and 12: the fans of its polygon and inner nodes)
    tris = np.empty((node_offsets[n_aff] + 12 * n_aff, 3), np.int64)
    parent = np.empty(tris.shape[0], np.int64)
    n_tris = np.int64(0)
    new_node = np.empty(4 * k_nodes + 4, np.int64)
    new_src = np.zeros((4 * k_nodes + 4, 3), np.int64)
    new_coef = np.zeros((4 * k_nodes + 4, 3))
    n_new = np.int64(0)
    head = np.full(k_nodes, -1, np.int64)           # the new vertices of each node, chained
    chain = np.empty(4 * k_nodes + 4, np.int64)
    local = np.empty((k_nodes + 16, 3), np.int64)
    work = (np.empty(k_nodes + 3, np.int64), np.zeros(k_nodes + 3, np.bool_), np.empty(k_nodes + 3),
            np.empty(k_nodes + 3, np.int64), np.zeros(k_nodes + 3, np.bool_))
    path, welded = (path_int, path_float), (wpos, wfaces, face_edges, edges)
    for a in range(n_aff):
        f = affected[a]
        n_local = _triangulate_face(f, node_list[node_offsets[a]:node_offsets[a + 1]], path, welded, local, on_edge,
                                    work)
        for i in range(n_local):
            for c in range(3):
                code = local[i, c]
                if code < 0:                                   # a corner of the face
                    tris[n_tris, c] = faces[f, -1 - code]
                elif path_int[code, KIND] == VERTEX:              # a corner that is on the path
                    k = 0
                    while wfaces[f, k] != path_int[code, ID]:
                        k += 1
                    tris[n_tris, c] = faces[f, k]
                else:                                          # a new vertex
                    if n_new + 1 >= new_node.shape[0]:
                        new_node = np.concatenate((new_node, np.empty_like(new_node)))
                        new_src = np.concatenate((new_src, np.zeros_like(new_src)))
                        new_coef = np.concatenate((new_coef, np.zeros_like(new_coef)))
                        chain = np.concatenate((chain, np.empty_like(chain)))
                    vid, n_new = _new_vertex(code, f, path, faces, welded,
                                             (new_node, new_src, new_coef, head, chain), n_new)
                    tris[n_tris, c] = n_vertices + vid
            parent[n_tris] = a
            n_tris += 1
    return (affected, tris[:n_tris].copy(), new_node[:n_new].copy(), new_src[:n_new].copy(),
            new_coef[:n_new].copy(), parent[:n_tris].copy())
