"""Step 4 of a tear stroke: the path along the tear plane's section of the surface."""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import F1, S1, helper, i8, kernel
from ...generated.kernels import segment_plane
from ..surface import WELDED_MESH
from .records import EDGE, EDGE_CARRIER, FACE, FACE_CARRIER, NO_CARRIER, VERTEX, Ends, Path


@helper
def _elements(g, wfaces, face_edges, cls, kinds, ids):
    """Where the plane meets face ``g``'s boundary: its corners on the plane (VERTEX, welded id) and
    its edges whose ends lie on opposite sides (EDGE, edge id). Returns how many (<= 3)."""
    count = 0
    for k in range(3):
        w = wfaces[g, k]
        if cls[w] == 0:
            kinds[count], ids[count] = VERTEX, w
            count += 1
    for k in range(3):
        if cls[wfaces[g, k]] * cls[wfaces[g, (k + 1) % 3]] < 0:
            kinds[count], ids[count] = EDGE, face_edges[g, k]
            count += 1
    return count


@helper
def _push(ni, nf, target, n, kind, ident, t, x, y, z, parent, carrier_kind, carrier, is_target):
    """Append a node of the search tree; its length is its parent's plus the step."""
    ni[n, 0], ni[n, 1], ni[n, 2], ni[n, 3], ni[n, 4] = kind, ident, parent, carrier_kind, carrier
    nf[n, 0], nf[n, 1], nf[n, 2], nf[n, 3] = t, x, y, z
    step = math.sqrt((x - nf[parent, 1]) ** 2 + (y - nf[parent, 2]) ** 2 + (z - nf[parent, 3]) ** 2)
    nf[n, 4] = nf[parent, 4] + step
    target[n] = is_target
    return n + 1


@helper
def _push_element(ni, nf, target, n, kind, ident, parent, carrier_kind, carrier, plane, wpos, edges,
                  t_kind, t_id, vertex_used):
    """Append the node for a boundary element (a vertex on the plane, or the crossing of an edge,
    computed by the generated ``segment_plane`` on the edge's welded ends in canonical order so that
    every copy of a seam edge gets the same point). Returns the new count, unchanged when the element
    is a vertex the path already went through (the front dies there: no self-crossing path)."""
    is_target = t_kind == kind and ident == t_id
    if kind == VERTEX:
        if vertex_used[ident] and not is_target:
            return n
        vertex_used[ident] = True
        p = wpos[ident]
        return _push(ni, nf, target, n, VERTEX, ident, 0.0, p[0], p[1], p[2], parent, carrier_kind,
                     carrier, is_target)
    t, x, y, z = segment_plane(plane, wpos[edges[ident, 0]], wpos[edges[ident, 1]])
    return _push(ni, nf, target, n, EDGE, ident, t, x, y, z, parent, carrier_kind, carrier, is_target)


@kernel((WELDED_MESH, S1, F1, i8, i8, F1, i8, i8, F1), cost=2.1)
def _walk(mesh, cls, plane, s_kind, s_id, s_pos, t_kind, t_id, t_pos):
    """Follow the plane's section of the surface from the start node to the target node.

    Nodes are (kind, id): VERTEX (welded vertex on the plane), EDGE (edge crossed by the plane, at
    its crossing point), FACE (a point inside a face: the start or the target, at s_pos / t_pos);
    the start and the target may be of any kind. The search grows fronts
    from the start along every direction the section leaves it by (two, or more at a saddle), always
    advancing the shortest one, so the first front to pop the target is the shorter way round.
    Each face (and each in-plane edge) is crossed at most once, which bounds the search by the face
    count and keeps fronts from looping.

    mesh : WeldedMesh (as a tuple) ; cls : (w,) int8 sides of the welded vertices ; plane : (4,)
    returns found (bool), and the fields of ``Path`` from start to target
    """
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    m = wfaces.shape[0]
    cap = m + edges.shape[0] + 4
    ni = np.empty((cap, 5), np.int64)         # kind, id, parent, carrier kind, carrier
    nf = np.empty((cap, 5))                   # t, x, y, z, length from the start
    target = np.zeros(cap, np.bool_)
    open_ = np.empty(cap, np.int64)
    face_used = np.zeros(m, np.bool_)
    edge_used = np.zeros(edges.shape[0], np.bool_)
    vertex_used = np.zeros(wpos.shape[0], np.bool_)
    kinds = np.empty(3, np.int64)
    ids = np.empty(3, np.int64)

    ni[0, 0], ni[0, 1], ni[0, 2], ni[0, 3], ni[0, 4] = s_kind, s_id, -1, NO_CARRIER, -1
    nf[0, 0], nf[0, 1], nf[0, 2], nf[0, 3], nf[0, 4] = 0.0, s_pos[0], s_pos[1], s_pos[2], 0.0
    if s_kind == EDGE:
        nf[0, 0] = segment_plane(plane, wpos[edges[s_id, 0]], wpos[edges[s_id, 1]])[0]
    if s_kind == VERTEX:
        vertex_used[s_id] = True
    n = np.int64(1)
    open_[0] = 0
    n_open = 1
    found = -1
    while n_open > 0:
        # the shortest open front
        best = 0
        for q in range(1, n_open):
            if nf[open_[q], 4] < nf[open_[best], 4]:
                best = q
        node = open_[best]
        n_open -= 1
        open_[best] = open_[n_open]
        if target[node]:
            found = node
            break
        if n + 8 > cap:
            break
        kind, ident, ck, cid = ni[node, 0], ni[node, 1], ni[node, 3], ni[node, 4]
        before = n
        if kind == FACE:
            # the start inside a face: the section leaves it at both ends of its chord
            g = ident
            face_used[g] = True
            count = _elements(g, wfaces, face_edges, cls, kinds, ids)
            for q in range(count):
                n = _push_element(ni, nf, target, n, kinds[q], ids[q], node, FACE_CARRIER, g, plane,
                                  wpos, edges, t_kind, t_id, vertex_used)
        elif kind == EDGE:
            # across the edge into each other face on it (one on a manifold edge)
            for r in range(ef_offsets[ident], ef_offsets[ident + 1]):
                g = ef_faces[r]
                if face_used[g] or (ck == FACE_CARRIER and g == cid):
                    continue
                face_used[g] = True
                if t_kind == FACE and g == t_id:
                    n = _push(ni, nf, target, n, FACE, g, 0.0, t_pos[0], t_pos[1], t_pos[2], node,
                              FACE_CARRIER, g, np.bool_(True))
                    continue
                count = _elements(g, wfaces, face_edges, cls, kinds, ids)
                exits = 0
                ek, eid = np.int64(-1), np.int64(-1)
                for q in range(count):
                    if not (kinds[q] == EDGE and ids[q] == ident):
                        exits += 1
                        ek, eid = kinds[q], ids[q]
                if exits == 1:       # 0: the section ends (cannot happen); > 1: g lies in the plane
                    n = _push_element(ni, nf, target, n, ek, eid, node, FACE_CARRIER, g, plane, wpos,
                                      edges, t_kind, t_id, vertex_used)
        else:
            # through a vertex on the plane: every face of its fan that the plane crosses from it,
            # and every edge from it that lies in the plane
            for r in range(vf_offsets[ident], vf_offsets[ident + 1]):
                g = vf_faces[r]
                if face_used[g] or (ck == FACE_CARRIER and g == cid):
                    continue
                k = 0
                while wfaces[g, k] != ident:
                    k += 1
                x, y = wfaces[g, (k + 1) % 3], wfaces[g, (k + 2) % 3]
                if t_kind == FACE and g == t_id:
                    face_used[g] = True
                    n = _push(ni, nf, target, n, FACE, g, 0.0, t_pos[0], t_pos[1], t_pos[2], node,
                              FACE_CARRIER, g, np.bool_(True))
                    continue
                if cls[x] * cls[y] < 0:
                    face_used[g] = True
                    n = _push_element(ni, nf, target, n, EDGE, face_edges[g, (k + 1) % 3], node,
                                      FACE_CARRIER, g, plane, wpos, edges, t_kind, t_id, vertex_used)
                    continue
                for side in range(2):
                    z = x if side == 0 else y
                    e = face_edges[g, k] if side == 0 else face_edges[g, (k + 2) % 3]
                    if cls[z] != 0 or edge_used[e] or (ck == EDGE_CARRIER and e == cid):
                        continue
                    if ef_offsets[e + 1] - ef_offsets[e] < 2:
                        continue     # a boundary edge: the surface is already open there
                    edge_used[e] = True
                    n = _push_element(ni, nf, target, n, VERTEX, z, node, EDGE_CARRIER, e, plane,
                                      wpos, edges, t_kind, t_id, vertex_used)
        for q in range(before, n):
            open_[n_open] = q
            n_open += 1

    if found < 0:
        return False, np.empty((0, 4), np.int64), np.empty((0, 4))
    length = 0
    q = found
    while q >= 0:
        length += 1
        q = ni[q, 2]
    path_int = np.empty((length, 4), np.int64)
    path_float = np.empty((length, 4))
    q = found
    for r in range(length - 1, -1, -1):
        path_int[r, 0], path_int[r, 1] = ni[q, 0], ni[q, 1]
        path_int[r, 2], path_int[r, 3] = ni[q, 3], ni[q, 4]
        for c in range(4):
            path_float[r, c] = nf[q, c]
        q = ni[q, 2]
    return True, path_int, path_float


def walk(surface, ends: Ends) -> Path | None:
    """Step 4 on ``surface`` (``surface._Surface``): the path from S_i to S_{i+1} along the section
    (None when the section does not lead there); a one-segment path gets its midpoint."""
    (s_kind, s_id), (t_kind, t_id) = ends.nodes.tolist()      # Python ints: cheaper than numpy scalars
    s_pos, t_pos = ends.points
    if s_kind == FACE and t_kind == FACE and s_id == t_id:
        path = Path(np.array([[FACE, s_id, NO_CARRIER, -1], [FACE, s_id, FACE_CARRIER, s_id]], np.int64),
                    np.array([[0.0, *s_pos], [0.0, *t_pos]]))
    else:
        found, nodes, points = _walk(tuple(surface.welded), ends.sides, ends.plane, s_kind, s_id, s_pos,
                                     t_kind, t_id, t_pos)
        if not found:
            return None
        path = Path(nodes, points)
    return _insert_midpoint(path, surface.welded) if len(path.nodes) == 2 else path


def _insert_midpoint(path, mesh) -> Path:
    """A one-segment path gets its midpoint as a third node, so that the slit has a vertex to split
    (with both ends kept single, a single edge could not open)."""
    path_int, path_float = path
    kind, carrier = path_int[1, 2], path_int[1, 3]
    p0, p1 = path_float[0, 1:4], path_float[1, 1:4]
    if kind == FACE_CARRIER:
        mid_int = [FACE, carrier, FACE_CARRIER, carrier]
        mid_float = [0.0, *(0.5 * (p0 + p1))]
    else:                                      # along an edge in the plane: its midpoint
        lo, hi = mesh.positions[mesh.edges[carrier]]
        mid_int = [EDGE, carrier, EDGE_CARRIER, carrier]
        mid_float = [0.5, *(0.5 * (lo + hi))]
    return Path(np.array([path_int[0], mid_int, path_int[1]], np.int64),
                np.array([path_float[0], mid_float, path_float[1]]))
