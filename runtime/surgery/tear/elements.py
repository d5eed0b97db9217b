"""Step 4 of a tear stroke, the elements of the walk: where the tear plane meets a face's boundary, and
the nodes of the search tree."""
import math

import numpy as np

from ..._shared.jit import helper, inlined
from ...generated.kernels import segment_plane
from .records import CARRIER, CARRIER_KIND, EDGE, EDGE_CARRIER, EDGE_T, ID, KIND, LENGTH, PARENT, POINT, VERTEX
from .region import _outside


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


@inlined
def _step(nf, parent, x, y, z):
    """The distance from the walk's node ``parent`` to (x, y, z)."""
    return math.sqrt((x - nf[parent, POINT]) ** 2 + (y - nf[parent, POINT + 1]) ** 2 + (z - nf[parent, POINT + 2]) ** 2)


@inlined
def _push(table, n, kind, ident, at, parent, carrier_kind, carrier, is_target):
    """Append node n to the walk's ``NodeTable``: the element (kind, ident) at ``at`` (t, x, y, z),
    reached from ``parent`` through the carrier; its length is its parent's plus the step. Returns
    n + 1."""
    ni, nf = table.ints, table.floats
    t, x, y, z = at
    ni[n, KIND], ni[n, ID], ni[n, PARENT] = kind, ident, parent
    ni[n, CARRIER_KIND], ni[n, CARRIER] = carrier_kind, carrier
    nf[n, EDGE_T], nf[n, POINT], nf[n, POINT + 1], nf[n, POINT + 2] = t, x, y, z
    nf[n, LENGTH] = nf[parent, LENGTH] + _step(nf, parent, x, y, z)
    table.target[n] = is_target
    return n + 1


@helper
def _push_target(table, n, goal, parent, carrier_kind, carrier):
    """Append the walk's ``Target`` ``goal`` as node n, reached from ``parent`` through the carrier (a
    call: once a walk, where ``_push`` is typed into ``_push_element``, once a node)."""
    return _push(table, n, goal.kind, goal.ident, (goal.t, goal.x, goal.y, goal.z), parent, carrier_kind, carrier,
                 np.bool_(True))


@helper
def _element_point(kind, ident, plane, wpos, edges):
    """(t, x, y, z) of a boundary element: a vertex on the plane (t = 0), or the crossing of an edge,
    computed by the generated ``segment_plane`` on the edge's welded ends in canonical order so that
    every copy of a seam edge gets the same point."""
    if kind == VERTEX:
        p = wpos[ident]
        return 0.0, p[0], p[1], p[2]
    return segment_plane(plane, wpos[edges[ident, 0]], wpos[edges[ident, 1]])


@helper
def _push_element(table, n, kind, ident, parent, carrier_kind, carrier, plane, wpos, edges, goal, reach):
    """Append the node for a boundary element (``_element_point``) to the walk's ``NodeTable``.
    Returns the new count, unchanged when the element lies outside the walk's ``Reach``: outside the
    swept region (``region.py``: the front dies there, no detour), or a vertex that a path as short or
    shorter already reached (so no self-crossing path, and where the plane holds edges and faces, which
    reach a vertex by several ways, the shortest wins: the walk drops a vertex's node that a shorter one
    superseded when it pops it)."""
    nf, vertex_used = table.floats, reach.vertex_used
    is_target = goal.kind == kind and ident == goal.ident
    at = _element_point(kind, ident, plane, wpos, edges)
    _, x, y, z = at
    if kind == VERTEX and not is_target:
        length = nf[parent, LENGTH] + _step(nf, parent, x, y, z)
        if not length < vertex_used[ident]:
            return n
    if not is_target:
        # within the margin of S_i (the root: in the hull) is within the region; else measure
        margin = reach.margin
        near = (x - nf[0, POINT]) ** 2 + (y - nf[0, POINT + 1]) ** 2 + (z - nf[0, POINT + 2]) ** 2 <= margin * margin
        if not near and _outside((x, y, z), reach.region) > margin:
            return n
    if kind == VERTEX:
        vertex_used[ident] = min(vertex_used[ident], nf[parent, LENGTH] + _step(nf, parent, x, y, z))  # as _push
    return _push(table, n, kind, ident, at, parent, carrier_kind, carrier, is_target)


@helper
def _in_plane(e, edges, cls):
    """Whether edge e lies in the plane (both its welded ends on it)."""
    return cls[edges[e, 0]] == 0 and cls[edges[e, 1]] == 0


@helper
def _edge_parameter(e, point, cls, plane, wpos, edges):
    """Parameter t (from ``edges[e, 0]``) of a path node on edge e at ``point``: the crossing's, by the
    generated ``segment_plane``, for an edge whose ends lie on opposite sides; for an edge lying in the
    plane (where that crossing is undefined), the point's projection onto the edge."""
    lo, hi = wpos[edges[e, 0]], wpos[edges[e, 1]]
    if not _in_plane(e, edges, cls):
        return segment_plane(plane, lo, hi)[0]
    num, den = 0.0, 0.0
    for k in range(3):
        num += (point[k] - lo[k]) * (hi[k] - lo[k])
        den += (hi[k] - lo[k]) ** 2
    return min(max(num / den, 0.0), 1.0) if den > 0.0 else 0.5


@helper
def _along_edge(table, n, node, e, plane, wpos, edges, goal, reach):
    """From a path node on edge e lying in the plane (a point of it, not a corner): along the edge, to
    the target when it lies on the same edge, else to both ends of the edge (the section there is the
    edge itself: the faces on it lie on either side, or in the plane, whose own edges go on)."""
    if goal.kind == EDGE and goal.ident == e:
        return _push_target(table, n, goal, node, EDGE_CARRIER, e)
    for side in range(2):
        n = _push_element(table, n, VERTEX, edges[e, side], node, EDGE_CARRIER, e, plane, wpos, edges, goal, reach)
    return n
