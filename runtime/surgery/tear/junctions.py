"""Step 4 of a tear stroke, where the section meets an opening of the surface: the boundary points on
the plane across it, and whether the path may jump there (an X junction across an existing slit, or a T
junction onto it)."""
import math

import numpy as np

from ..._shared.jit import helper
from ...algebra.vec3 import _dot, _norm, _sub
from ..bvh import _first_hit
from .elements import _element_point, _elements, _push_element
from .records import EDGE, ID, JUMP_CARRIER, KIND, PARENT, POINT, VERTEX
from .region import _outside

@helper
def _openings(cls, edges, ef_offsets, plane, wpos, region, margin):
    """Where the plane meets the surface's boundary inside the swept region: (c, 2) int64 (kind, id)
    of the boundary edges it crosses (EDGE) and the boundary vertices on it (VERTEX)."""
    found = np.empty((16, 2), np.int64)
    count = 0
    # (a vertex is met once per boundary edge at it; an existing slit along the plane has hundreds)
    vertex_seen = np.zeros(wpos.shape[0], np.bool_)
    for e in range(edges.shape[0]):
        if ef_offsets[e + 1] - ef_offsets[e] != 1:
            continue
        for kind, ident in ((EDGE, e), (VERTEX, edges[e, 0]), (VERTEX, edges[e, 1])):
            if kind == EDGE and cls[edges[e, 0]] * cls[edges[e, 1]] >= 0:
                continue
            if kind == VERTEX and (cls[ident] != 0 or vertex_seen[ident]):
                continue
            if kind == VERTEX:
                vertex_seen[ident] = True
            if _outside(_element_point(kind, ident, plane, wpos, edges)[1:], region) > margin:
                continue
            if count == found.shape[0]:
                found = np.concatenate((found, np.empty_like(found)))
            found[count, 0], found[count, 1] = kind, ident
            count += 1
    return found[:count]


@helper
def _unit(u):
    length = _norm(u)
    for k in range(3):
        u[k] /= max(length, 1e-300)
    return u


@helper
def _jump(bvh, mesh, cls, plane, p_kind, p_id, p, before, q_kind, q_id, q, snap):
    """Whether the path may jump from boundary point p (reached from ``before``, None when p is the
    start) to boundary point q through an opening of the surface: the two sides of a closed slit
    (within ``snap`` of each other), or two boundary points (edge crossings, or vertices on the plane
    -- a plane through a vertex of an opened slit meets its side there -- but for a start at a vertex)
    with no face between them, the jump going on the way the section arrives at p and leaves q into
    its faces (so never back, nor along a slit, nor over the skin from one slit to another). (A start
    at a vertex on the boundary is the tip of a slit the stroke continues: from there, the slit itself
    is an opening along which another point of it can be in the plane.)"""
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    d = _sub(q, p)
    length = _norm(d)
    if length > snap and before is None and p_kind == VERTEX:
        return False
    for kind, w in ((p_kind, p_id), (q_kind, q_id)):
        # not where the opening runs along the plane (an end on a boundary edge lying in it): a jump
        # between its two sides would follow the slit, not cross it
        if kind == VERTEX and _boundary_vertex(w, wfaces, face_edges, ef_offsets, vf_offsets, vf_faces, cls, True):
            return False
    if length <= snap:
        return True                          # across a closed slit
    d = _unit(d)
    if before is not None and _dot(d, _sub(p, before)) < 0.0:
        return False
    if not _leaves_ahead(mesh, cls, plane, q_kind, q_id, p, d):
        return False
    s = min(0.25, snap / length + 1e-7)      # the ends lie on faces: leave them out
    a, b = np.empty(3), np.empty(3)
    for k in range(3):
        a[k] = p[k] + s * length * d[k]
        b[k] = q[k] - s * length * d[k]
    return _first_hit(bvh, a, b)[0] < 0


@helper
def _leaves_ahead(mesh, cls, plane, q_kind, q_id, p, d):
    """Whether the section leaves boundary point q only ahead of p along direction ``d`` (3,) (the jump
    from p to q): into q's one face (q on a boundary edge), or into each face of q's fan that the plane
    crosses from it and along each edge from it that lies in the plane (q a vertex on the plane). (Ahead
    of p, not of q: beside the end of a slit opened wide, a thin face of its far side can fold over the
    gap, and the section turns back across it before it goes on.)"""
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    kinds, ids = np.empty(3, np.int64), np.empty(3, np.int64)
    if q_kind == EDGE:
        lo, hi = ef_offsets[q_id], ef_offsets[q_id] + 1
    else:
        lo, hi = vf_offsets[q_id], vf_offsets[q_id + 1]
    for r in range(lo, hi):
        g = ef_faces[r] if q_kind == EDGE else vf_faces[r]
        count = _elements(g, wfaces, face_edges, cls, kinds, ids)
        for c in range(count):
            if kinds[c] == q_kind and ids[c] == q_id:
                continue
            _, x, y, z = _element_point(kinds[c], ids[c], plane, wpos, edges)
            if (x - p[0]) * d[0] + (y - p[1]) * d[1] + (z - p[2]) * d[2] <= 0.0:
                return False
    return True


@helper
def _boundary_vertex(w, wfaces, face_edges, ef_offsets, vf_offsets, vf_faces, cls, in_plane):
    """Whether welded vertex w lies on the boundary (an edge from it has one face); with ``in_plane``,
    on a boundary edge that lies in the plane (its other end on the plane too)."""
    for r in range(vf_offsets[w], vf_offsets[w + 1]):
        g = vf_faces[r]
        for k in range(3):
            if wfaces[g, k] == w:
                for side in range(2):
                    e = face_edges[g, k] if side == 0 else face_edges[g, (k + 2) % 3]
                    other = wfaces[g, (k + 1) % 3] if side == 0 else wfaces[g, (k + 2) % 3]
                    if ef_offsets[e + 1] - ef_offsets[e] == 1 and (not in_plane or cls[other] == 0):
                        return True
    return False


@helper
def _behind(table, node, length):
    """(3,) where the walk's way to ``node`` was ``length`` before it: the point of its nearest ancestor
    at least that far from it (the start's when none is), None when ``node`` is the start. (Not just
    its parent's: beside a slit opened wide, a thin face of it can fold over the gap, and the section
    turns back across it just before the boundary.)"""
    ni, nf = table.ints, table.floats
    if ni[node, PARENT] < 0:
        return None
    q = node
    while ni[q, PARENT] >= 0:
        q = ni[q, PARENT]
        d2 = 0.0
        for c in range(3):
            d2 += (nf[q, POINT + c] - nf[node, POINT + c]) ** 2
        if d2 >= length * length:
            break
    return nf[q, POINT:POINT + 3]


@helper
def _jumps(node, table, n, openings, jumped, bvh, mesh, cls, plane, goal, reach, snap):
    """Push the jumps from boundary node ``node`` of the walk's ``NodeTable`` to the ``openings``
    (``_openings``) not yet jumped to that ``_jump`` allows (at most one node per opening: the walk
    makes room for them first); returns the new node count."""
    wpos, edges = mesh[0], mesh[3]
    ni, nf = table.ints, table.floats
    kind, ident = ni[node, KIND], ni[node, ID]
    at = nf[node, POINT:POINT + 3]
    to = np.empty(3)
    for c in range(openings.shape[0]):
        ok, oid = openings[c, 0], openings[c, 1]
        if jumped[c] or (ok == kind and oid == ident):
            continue
        _, to[0], to[1], to[2] = _element_point(ok, oid, plane, wpos, edges)
        length = math.sqrt((to[0] - at[0]) ** 2 + (to[1] - at[1]) ** 2 + (to[2] - at[2]) ** 2)
        came_from = _behind(table, node, length) if length > snap else None   # (a closed slit's jump needs none)
        if _jump(bvh, mesh, cls, plane, kind, ident, at, came_from, ok, oid, to, snap):
            jumped[c] = True
            n = _push_element(table, n, ok, oid, node, JUMP_CARRIER, np.int64(-1), plane, wpos, edges, goal, reach)
    return n
