"""Step 4 of a tear stroke, across faces that lie in the tear plane (a flat part of the surface that the
blade lies along): there the plane's section is not a curve but the faces themselves, and the walk
follows the straight line from S_i towards S_{i+1} over them -- the section of those faces by the
plane Q through S_i and S_{i+1} perpendicular to the tear plane -- instead of their edges.

Q is used only inside such faces: every node found there lies on the tear plane (on an edge of a flat
face, both of whose ends are on it), so the rest of the tear (re-triangulation, slit) sees ordinary
nodes on edges that lie in the plane. A welded vertex's side of Q is decided once, with the same
tolerance as its side of the tear plane, by the same computation wherever it is asked.
"""
import math

import numpy as np

from ..._shared.jit import helper
from ...generated.kernels import point_plane_distance
from .elements import _push_element, _push_target
from .records import EDGE, FACE, FACE_CARRIER, VERTEX


@helper
def _flat(g, wfaces, cls):
    """Whether face g lies in the tear plane (its three welded corners on it)."""
    return cls[wfaces[g, 0]] == 0 and cls[wfaces[g, 1]] == 0 and cls[wfaces[g, 2]] == 0


@helper
def _line_plane(plane, s_pos, t_pos):
    """Q: the plane through S_i and S_{i+1} perpendicular to the tear plane, (4,) n̂ + d e∞ (its
    section of a flat face is the straight line from S_i to S_{i+1})."""
    n = plane[:3]
    d0, d1, d2 = t_pos[0] - s_pos[0], t_pos[1] - s_pos[1], t_pos[2] - s_pos[2]
    q = np.empty(4)
    q[0], q[1], q[2] = n[1] * d2 - n[2] * d1, n[2] * d0 - n[0] * d2, n[0] * d1 - n[1] * d0
    length = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2)
    for k in range(3):
        q[k] /= max(length, 1e-300)
    q[3] = q[0] * s_pos[0] + q[1] * s_pos[1] + q[2] * s_pos[2]
    return q


@helper
def _line_side(w, line, wpos, tol):
    """Side of welded vertex w of Q: +1 / -1, or 0 within ``tol``."""
    d = point_plane_distance(line, wpos[w])
    return 0 if abs(d) <= tol else (1 if d > 0.0 else -1)


@helper
def _line_exits(g, wfaces, face_edges, line, wpos, tol, kinds, ids):
    """Where Q meets flat face g's boundary: its corners on Q (VERTEX) and its edges whose ends lie on
    opposite sides of Q (EDGE). Returns how many (<= 3)."""
    side = np.empty(3, np.int64)
    for k in range(3):
        side[k] = _line_side(wfaces[g, k], line, wpos, tol)
    count = 0
    for k in range(3):
        if side[k] == 0:
            kinds[count], ids[count] = VERTEX, wfaces[g, k]
            count += 1
    for k in range(3):
        if side[k] * side[(k + 1) % 3] < 0:
            kinds[count], ids[count] = EDGE, face_edges[g, k]
            count += 1
    return count


@helper
def _across_flat(table, n, node, g, skip_kind, skip_id, line, mesh, tol, goal, reach):
    """From path node ``node`` on the boundary of flat face g (the element ``skip_kind``, ``skip_id``:
    a corner, or a point of an edge) or inside it (the start, -1), straight on across g: to the target
    when it is inside g or on an edge of g that Q (``line``) leaves by, else to where Q leaves g, never
    back nor along g's border; the segments run across g (FACE_CARRIER). Edge points are Q's crossings
    (generated ``segment_plane``). ``mesh``: WeldedMesh (as a tuple). Returns the new node count."""
    wpos, wfaces, face_edges, edges = mesh[0], mesh[1], mesh[2], mesh[3]
    if goal.kind == FACE and goal.ident == g:              # the target inside g
        return _push_target(table, n, goal, node, FACE_CARRIER, g)
    kinds, ids = np.empty(3, np.int64), np.empty(3, np.int64)
    count = _line_exits(g, wfaces, face_edges, line, wpos, tol, kinds, ids)
    for c in range(count):
        if kinds[c] == skip_kind and ids[c] == skip_id:
            continue
        # never along g's border: from a corner only to the opposite side, from a point of an edge not
        # to that edge's ends (Q holding that edge: the walk goes along it instead)
        if skip_kind == VERTEX and kinds[c] == VERTEX:
            continue
        if skip_kind == EDGE and kinds[c] == VERTEX and (ids[c] == edges[skip_id, 0] or ids[c] == edges[skip_id, 1]):
            continue
        if kinds[c] == EDGE and goal.kind == EDGE and ids[c] == goal.ident:
            n = _push_target(table, n, goal, node, FACE_CARRIER, g)
            continue
        n = _push_element(table, n, kinds[c], ids[c], node, FACE_CARRIER, g, line, wpos, edges, goal, reach)
    return n
