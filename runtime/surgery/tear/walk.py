"""Step 4 of a tear stroke: the path along the tear plane's section of the surface."""
from __future__ import annotations

import numpy as np

from ..._shared.jit import F1, I1, S1, callee, f8, helper, i8, inlined, record
from ..bvh import BVH_ARRAYS
from ..surface import WELDED_MESH
from .elements import _along_edge, _edge_parameter, _elements, _in_plane, _push_element, _push_target
from .flat import _across_flat, _flat, _line_plane, _line_side
from .junctions import _boundary_vertex, _jumps, _openings
from .records import (CARRIER, CARRIER_KIND, EDGE, EDGE_CARRIER, EDGE_T, FACE, FACE_CARRIER, ID, JUMP_CARRIER,
                      KIND, LENGTH, NO_CARRIER, PARENT, POINT, VERTEX, NodeTable, Reach, Target)
from .region import _beyond_the_blade, _margin


@callee((WELDED_MESH, S1, F1, record(i8, i8, F1), record(i8, i8, F1), BVH_ARRAYS, record(F1, F1, F1, F1), I1, f8),
        cost=12.0)
def _walk(mesh, cls, plane, start, target, bvh, region, hit_faces, snap):
    """``_walk_within`` with a node table first sized for a node per face and per edge of the patch,
    which the walks seen fill a small part of (it grows if one ever needs more)."""
    capacity = mesh[1].shape[0] + mesh[3].shape[0] + 4
    return _walk_within(mesh, cls, plane, start, target, bvh, region, hit_faces, snap, capacity)


@helper
def _walk_within(mesh, cls, plane, start, target, bvh, region, hit_faces, snap, capacity):
    """Follow the plane's section of the surface from the start node to the target node.

    Nodes are (kind, id): VERTEX (welded vertex on the plane), EDGE (edge crossed by the plane, at
    its crossing point), FACE (a point inside a face: the start or the target, at its point);
    the start and the target (``records.WalkEnd``: kind, id, point) may be of any kind. The search grows fronts
    from the start along every direction the section leaves it by (two, or more at a saddle), always
    advancing the shortest one, so the first front to pop the target is the shorter way round.
    Each face (and each in-plane edge) is crossed at most once, which bounds the search by the face
    count and keeps fronts from looping. A front dies where it leaves the swept region (``region``,
    ``margin``: see region.py); where an opening stopped a front, a path that goes beyond the blade's
    tip (round the far side of a limb, which the margin may hold) is none. A front that reaches the
    surface's boundary (an existing slit, a hole, a border) may jump through the opening to a boundary
    point across it on the plane in the region (``_jump``): the new slit then crosses the old one (an X
    junction), or ends on it (a T junction) when the target is there.

    mesh : WeldedMesh (as a tuple) ; cls : (w,) int8 sides of the welded vertices ; plane : (4,)
    bvh : BVHArrays (as a tuple) of the surface ; region : the blade at both times, (a0, b0, a1, b1)
    (3,) each ; hit_faces : (2,) the faces it hit
    snap : absolute distance ; capacity : the node table's first size (>= 1): before each node is
    expanded it grows to hold every node that expansion may push (``_room``), so no walk stops short
    returns found (bool), and the fields of ``Path`` from start to target
    """
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    s_kind, s_id, s_pos = start
    t_kind, t_id, t_pos = target
    if s_kind == FACE and t_kind == FACE and s_id == t_id:
        # both ends inside one face: the chord between them
        # (arrays filled by element: numba types an array built from nested lists for seconds)
        path_int, path_float = np.empty((2, 4), np.int64), np.zeros((2, 4))
        path_int[0, KIND], path_int[0, ID], path_int[0, CARRIER_KIND], path_int[0, CARRIER] = FACE, s_id, NO_CARRIER, -1
        path_int[1, KIND], path_int[1, ID] = FACE, s_id
        path_int[1, CARRIER_KIND], path_int[1, CARRIER] = FACE_CARRIER, s_id
        for c in range(3):
            path_float[0, POINT + c], path_float[1, POINT + c] = s_pos[c], t_pos[c]
        return _with_midpoint(path_int, path_float, wpos, edges)
    margin = _margin(wpos, wfaces, hit_faces, s_pos, t_pos)
    m = wfaces.shape[0]
    cap = max(capacity, 1)
    table = NodeTable(np.empty((cap, PARENT + 1), np.int64), np.empty((cap, LENGTH + 1)), np.zeros(cap, np.bool_))
    fronts = np.empty(cap, np.int64)          # the open fronts: a heap (``_pop_front``), as long as the table
    face_used = np.zeros(m, np.bool_)
    edge_used = np.zeros(edges.shape[0], np.bool_)
    reach = Reach(np.full(wpos.shape[0], np.inf), region, margin)
    kinds = np.empty(3, np.int64)
    ids = np.empty(3, np.int64)
    openings = np.empty((0, 2), np.int64)   # boundary points on the plane, found when first needed
    jumped = np.empty(0, np.bool_)
    looked = False
    blocked = False                         # a front met an opening it could not cross

    ni, nf = table.ints, table.floats
    ni[0, KIND], ni[0, ID], ni[0, PARENT], ni[0, CARRIER_KIND], ni[0, CARRIER] = s_kind, s_id, -1, NO_CARRIER, -1
    nf[0, EDGE_T], nf[0, LENGTH] = 0.0, 0.0
    nf[0, POINT], nf[0, POINT + 1], nf[0, POINT + 2] = s_pos[0], s_pos[1], s_pos[2]
    if s_kind == EDGE:
        nf[0, EDGE_T] = _edge_parameter(s_id, s_pos, cls, plane, wpos, edges)
    goal = Target(t_kind, t_id, _edge_parameter(t_id, t_pos, cls, plane, wpos, edges) if t_kind == EDGE else 0.0,
                  t_pos[0], t_pos[1], t_pos[2])
    line = _line_plane(plane, s_pos, t_pos)
    if s_kind == VERTEX:
        reach.vertex_used[s_id] = 0.0
    n = np.int64(1)
    fronts[0] = 0
    n_open = np.int64(1)
    found = -1
    while n_open > 0:
        node, n_open = _pop_front(fronts, n_open, table.floats)
        ni, nf = table.ints, table.floats
        if table.target[node]:
            found = node
            break
        if ni[node, KIND] == VERTEX and nf[node, LENGTH] > reach.vertex_used[ni[node, ID]]:
            continue             # superseded: a shorter way reached this vertex (elements._push_element)
        kind, ident, ck, cid = ni[node, KIND], ni[node, ID], ni[node, CARRIER_KIND], ni[node, CARRIER]
        table, fronts = _room(table, fronts, n, _most_pushed(kind, ident, ef_offsets, vf_offsets))
        before = n
        if kind == FACE and _flat(ident, wfaces, cls):
            # the start inside a face lying in the plane: straight on towards S_(i+1) (flat.py)
            face_used[ident] = True
            n = _across_flat(table, n, node, ident, np.int64(-1), np.int64(-1), line, mesh, snap, goal, reach)
        elif kind == FACE:
            # the start inside a face: the section leaves it at both ends of its chord
            g = ident
            face_used[g] = True
            count = _elements(g, wfaces, face_edges, cls, kinds, ids)
            for q in range(count):
                n = _push_element(table, n, kinds[q], ids[q], node, FACE_CARRIER, g, plane, wpos, edges, goal, reach)
        elif kind == EDGE and _in_plane(ident, edges, cls):
            # a point of an edge lying in the plane: straight on across each face on it that lies in the
            # plane too; along the edge where a face on it does not (there the edge is the section, or
            # the border of a flat part), unless it is a boundary edge (the surface is open there)
            along = False
            for r in range(ef_offsets[ident], ef_offsets[ident + 1]):
                g = ef_faces[r]
                if not _flat(g, wfaces, cls):
                    along = True
                elif not (face_used[g] or (ck == FACE_CARRIER and g == cid)):
                    face_used[g] = True
                    n = _across_flat(table, n, node, g, EDGE, ident, line, mesh, snap, goal, reach)
            if along and ef_offsets[ident + 1] - ef_offsets[ident] >= 2:
                # (even when a front from one of its ends went along it: the way on from this point
                # may be the shorter one to the other end)
                edge_used[ident] = True
                n = _along_edge(table, n, node, ident, plane, wpos, edges, goal, reach)
        elif kind == EDGE:
            # across the edge into each other face on it (one on a manifold edge)
            for r in range(ef_offsets[ident], ef_offsets[ident + 1]):
                g = ef_faces[r]
                if face_used[g] or (ck == FACE_CARRIER and g == cid):
                    continue
                face_used[g] = True
                if t_kind == FACE and g == t_id:
                    n = _push_target(table, n, goal, node, FACE_CARRIER, g)
                    continue
                count = _elements(g, wfaces, face_edges, cls, kinds, ids)
                exits = 0
                ek, eid = np.int64(-1), np.int64(-1)
                for q in range(count):
                    if not (kinds[q] == EDGE and ids[q] == ident):
                        exits += 1
                        ek, eid = kinds[q], ids[q]
                if exits == 1:       # 0: the section ends (cannot happen); > 1: g lies in the plane
                    n = _push_element(table, n, ek, eid, node, FACE_CARRIER, g, plane, wpos, edges, goal, reach)
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
                    n = _push_target(table, n, goal, node, FACE_CARRIER, g)
                    continue
                if cls[x] == 0 and cls[y] == 0 and _line_side(ident, line, wpos, snap) == 0:
                    # a face lying in the plane, and the vertex on the line from S_i to S_(i+1): straight
                    # on across it (and round it by its edges, below)
                    face_used[g] = True
                    n = _across_flat(table, n, node, g, VERTEX, ident, line, mesh, snap, goal, reach)
                if cls[x] * cls[y] < 0:
                    face_used[g] = True
                    n = _push_element(table, n, EDGE, face_edges[g, (k + 1) % 3], node, FACE_CARRIER, g, plane, wpos,
                                      edges, goal, reach)
                    continue
                for side in range(2):
                    z = x if side == 0 else y
                    e = face_edges[g, k] if side == 0 else face_edges[g, (k + 2) % 3]
                    if cls[z] != 0 or edge_used[e] or (ck == EDGE_CARRIER and e == cid):
                        continue
                    if ef_offsets[e + 1] - ef_offsets[e] < 2:
                        continue     # a boundary edge: the surface is already open there
                    edge_used[e] = True
                    if t_kind == EDGE and t_id == e:      # the target lies on this edge: it ends there
                        n = _push_target(table, n, goal, node, EDGE_CARRIER, e)
                        continue
                    n = _push_element(table, n, VERTEX, z, node, EDGE_CARRIER, e, plane, wpos, edges, goal, reach)
        at_boundary = ((kind == EDGE and ef_offsets[ident + 1] - ef_offsets[ident] == 1)
                       or (kind == VERTEX and _boundary_vertex(ident, wfaces, face_edges, ef_offsets, vf_offsets,
                                                              vf_faces, cls, False)))
        if at_boundary and ck != JUMP_CARRIER:
            # at the boundary (not just arrived by a jump): through the opening to the points across it
            if not looked:
                looked = True
                openings = _openings(cls, edges, ef_offsets, plane, wpos, region, margin)
                jumped = np.zeros(openings.shape[0], np.bool_)
            table, fronts = _room(table, fronts, n, openings.shape[0])   # a jump per opening
            pushed = n
            n = _jumps(node, table, n, openings, jumped, bvh, mesh, cls, plane, goal, reach, snap)
            blocked = blocked or n == pushed
        for q in range(before, n):
            n_open = _push_front(fronts, n_open, q, table.floats)

    if found < 0:
        return False, np.empty((0, 4), np.int64), np.empty((0, 4))
    ni, nf = table.ints, table.floats
    # the path, leaf to root; a jump at either end only reaches a hit across an opening: the slit ends
    # where it meets the opening (no nodes at all when the path only jumps: nothing to tear)
    length = 0
    q = found
    while q >= 0:
        length += 1
        q = ni[q, PARENT]
    chain = np.empty(length, np.int64)
    q = found
    for r in range(length - 1, -1, -1):
        chain[r] = q
        q = ni[q, PARENT]
    if blocked and _beyond_the_blade(nf, chain, plane, region, snap):
        # round the far side, where an opening blocked the near way (region.py)
        return False, np.empty((0, 4), np.int64), np.empty((0, 4))
    first, last = 0, length - 1
    while last > 0 and ni[chain[last], CARRIER_KIND] == JUMP_CARRIER:
        last -= 1
    while first < last and ni[chain[first + 1], CARRIER_KIND] == JUMP_CARRIER:
        first += 1
    if first == last:
        return True, np.empty((0, 4), np.int64), np.empty((0, 4))
    path_int = np.empty((last - first + 1, 4), np.int64)
    path_float = np.empty((last - first + 1, 4))
    for r in range(first, last + 1):
        q = chain[r]
        path_int[r - first, KIND], path_int[r - first, ID] = ni[q, KIND], ni[q, ID]
        path_int[r - first, CARRIER_KIND], path_int[r - first, CARRIER] = ni[q, CARRIER_KIND], ni[q, CARRIER]
        for c in range(LENGTH):             # (a path point row is the table's row without its length)
            path_float[r - first, c] = nf[q, c]
    path_int[0, CARRIER_KIND], path_int[0, CARRIER] = NO_CARRIER, -1
    if path_int.shape[0] == 2:
        return _with_midpoint(path_int, path_float, wpos, edges)
    return True, path_int, path_float


@inlined
def _before(nf, a, b):
    """Whether the walk expands node ``a`` before node ``b``: the shorter way from the start first, then
    the node pushed first."""
    return nf[a, LENGTH] < nf[b, LENGTH] or (nf[a, LENGTH] == nf[b, LENGTH] and a < b)


@inlined
def _push_front(heap, size, node, nf):
    """Add ``node`` to the open fronts: ``heap``'s first ``size`` entries, a binary heap in the order of
    ``_before`` (``nf``: the node table's floats; the heap is as long as the table, so it has room);
    returns the new size."""
    i = size
    heap[i] = node
    while i > 0:
        up = (i - 1) // 2
        if not _before(nf, heap[i], heap[up]):
            break
        heap[i], heap[up] = heap[up], heap[i]
        i = up
    return size + 1


@inlined
def _pop_front(heap, size, nf):
    """(the first open front in the order of ``_before``, the heap's new size), taken off the heap."""
    node = heap[0]
    size -= 1
    heap[0] = heap[size]
    i = 0
    while True:
        first = 2 * i + 1
        if first >= size:
            break
        if first + 1 < size and _before(nf, heap[first + 1], heap[first]):
            first += 1
        if not _before(nf, heap[first], heap[i]):
            break
        heap[i], heap[first] = heap[first], heap[i]
        i = first
    return node, size


@helper
def _most_pushed(kind, ident, ef_offsets, vf_offsets):
    """The most nodes that expanding a node of ``kind``, ``ident`` pushes (its jumps aside): a face (the
    start) at most 3 (where the section or Q leaves it); a point of an edge 3 per face on the edge
    (``_across_flat``) and 2 along it; a vertex 5 per face of its fan (3 across a flat face, then one
    per edge from the vertex in the plane; or 1 where the plane crosses the face or it holds the
    target)."""
    if kind == FACE:
        return np.int64(3)
    if kind == EDGE:
        return 3 * (ef_offsets[ident + 1] - ef_offsets[ident]) + 2
    return 5 * (vf_offsets[ident + 1] - vf_offsets[ident])


@helper
def _room(table, fronts, n, need):
    """The walk's ``NodeTable`` and its fronts' heap (as long as the table) with room for ``need`` nodes
    after its first n: the same arrays, or copies at least twice as long (so a walk that outgrows its
    first size copies its nodes a few times in all; the heap is copied whole: it may hold every node)."""
    cap = table.ints.shape[0]
    if n + need <= cap:
        return table, fronts
    size = max(2 * cap, n + need)
    grown = NodeTable(np.empty((size, PARENT + 1), np.int64), np.empty((size, LENGTH + 1)), np.zeros(size, np.bool_))
    grown.ints[:n], grown.floats[:n], grown.target[:n] = table.ints[:n], table.floats[:n], table.target[:n]
    grown_fronts = np.empty(size, np.int64)
    grown_fronts[:cap] = fronts
    return grown, grown_fronts


@helper
def _with_midpoint(path_int, path_float, wpos, edges):
    """(True, path) with a one-segment path's midpoint as a third node, so that the slit has a vertex
    to split (with both ends kept single, a single edge could not open)."""
    kind, carrier = path_int[1, CARRIER_KIND], path_int[1, CARRIER]
    mid_int = np.empty(4, np.int64)
    mid_int[KIND], mid_int[ID], mid_int[CARRIER_KIND], mid_int[CARRIER] = EDGE, carrier, EDGE_CARRIER, carrier
    mid_float = np.empty(4)
    if kind == FACE_CARRIER:
        mid_int[KIND], mid_int[CARRIER_KIND] = FACE, FACE_CARRIER
        mid_float[EDGE_T] = 0.0
        for c in range(3):
            mid_float[POINT + c] = 0.5 * (path_float[0, POINT + c] + path_float[1, POINT + c])
    else:
        lo, hi = wpos[edges[carrier, 0]], wpos[edges[carrier, 1]]
        if path_int[0, KIND] == VERTEX and path_int[1, KIND] == VERTEX:
            # along a whole edge in the plane: its midpoint
            mid_float[EDGE_T] = 0.5
            for c in range(3):
                mid_float[POINT + c] = 0.5 * (lo[c] + hi[c])
        else:
            # along part of an edge in the plane (an end is a point of it): the middle of that part, at
            # the mean of the two ends' parameters on the edge (a corner's is 0 or 1)
            ts = np.empty(2)
            for r in range(2):
                corner = 1.0 if edges[carrier, 1] == path_int[r, ID] else 0.0
                ts[r] = path_float[r, EDGE_T] if path_int[r, KIND] == EDGE else corner
            t = 0.5 * (ts[0] + ts[1])
            mid_float[EDGE_T] = t
            for c in range(3):
                mid_float[POINT + c] = lo[c] + t * (hi[c] - lo[c])
    out_int, out_float = np.empty((3, 4), np.int64), np.empty((3, 4))
    out_int[0], out_int[1], out_int[2] = path_int[0], mid_int, path_int[1]
    out_float[0], out_float[1], out_float[2] = path_float[0], mid_float, path_float[1]
    return True, out_int, out_float

