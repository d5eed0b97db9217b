"""Steps 2-3 of a tear stroke: where the blade meets the skin at t_i and t_{i+1}, the tear plane,
and the side of every welded vertex."""
import math

import numpy as np

from ..._shared.jit import helper, inlined, kernel
from ...algebra.vec3 import _cross, _distance, _dot, _norm, _set_row, _sub
from ...generated.kernels import plane_from_points, point_plane_distance, segment_plane
from ...tolerances import tol
from ..bvh import _first_hit, _near_box, _push_children
from .records import EDGE, FACE, FROM_MISSES, ID, KIND, NO_MOTION, NO_PLANE, OK, VERTEX, Ends


@helper
def _classify(plane, welded_positions, tol, cls):
    """Side of every welded vertex: +1 / -1, or 0 within ``tol`` of the plane (signed distance up(x)·π
    through the generated kernel). Writes ``cls`` (w,) int8."""
    for w in range(welded_positions.shape[0]):
        d = point_plane_distance(plane, welded_positions[w])
        cls[w] = 0 if abs(d) <= tol else (1 if d > 0.0 else -1)


@helper
def _hit_node(face, hit, wfaces, wpos, tol):
    """(kind, id, point) of a scalpel hit: the nearest corner of the hit face when within ``tol``
    (VERTEX, welded id, its position), else (FACE, face, hit)."""
    best, best_d = -1, np.inf
    for k in range(3):
        d = _distance(wpos[wfaces[face, k]], hit)
        if d < best_d:
            best, best_d = wfaces[face, k], d
    if best_d <= tol:
        return VERTEX, best, wpos[best].copy()
    return FACE, face, hit.copy()


@helper
def _snap_to_edge(kind, ident, point, wfaces, face_edges, edges, wpos, cls, plane, tol):
    """A point inside a face within ``tol`` of where the plane crosses one of the face's edges is that
    crossing (an EDGE node), and one within ``tol`` of an edge of the face that lies in the plane (both
    ends on it) is the nearest point of that edge (an EDGE node too), so that a scalpel through an edge
    splits both faces on it instead of leaving a zero-area sliver beside it (and a point on an edge in
    the plane, where the section is the edge itself, is where the walk runs along it)."""
    if kind != FACE:
        return kind, ident, point
    for k in range(3):
        if cls[wfaces[ident, k]] == 0 and cls[wfaces[ident, (k + 1) % 3]] == 0:
            e = face_edges[ident, k]
            lo, hi = wpos[edges[e, 0]], wpos[edges[e, 1]]
            d = _sub(hi, lo)
            dd = _dot(d, d)
            if dd > 0.0:
                t = min(max(_dot(_sub(point, lo), d) / dd, 0.0), 1.0)
                nearest = np.empty(3)
                for c in range(3):
                    nearest[c] = lo[c] + t * d[c]
                if _distance(nearest, point) <= tol:
                    return EDGE, e, nearest
    for k in range(3):
        if cls[wfaces[ident, k]] * cls[wfaces[ident, (k + 1) % 3]] < 0:
            e = face_edges[ident, k]
            t, x, y, z = segment_plane(plane, wpos[edges[e, 0]], wpos[edges[e, 1]])
            if math.sqrt((x - point[0]) ** 2 + (y - point[1]) ** 2 + (z - point[2]) ** 2) <= tol:
                crossing = np.empty(3)
                crossing[0], crossing[1], crossing[2] = x, y, z
                return EDGE, e, crossing
    return kind, ident, point


@inlined
def _nearer(w, positions, a, d, dd, snap, best, best_t):
    """(best, best_t) with boundary vertex w taken when it is within ``snap`` of segment a -> a + d at a
    smaller parameter t than best_t (a lower vertex id at the same t)."""
    p = positions[w]
    t = min(max(((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / dd, 0.0), 1.0)
    if (t < best_t or (best >= 0 and t == best_t and w < best)) and math.sqrt(
            (a[0] + t * d[0] - p[0]) ** 2 + (a[1] + t * d[1] - p[1]) ** 2 + (a[2] + t * d[2] - p[2]) ** 2) <= snap:
        return w, t
    return best, best_t


@helper
def _boundary_near(bvh, positions, faces, flags, boundary, a, b, t_max, snap):
    """The boundary vertex within ``snap`` of segment a -> b with the smallest parameter t < t_max (then
    the lowest vertex id), as (vertex, t), or (-1, t_max). The boundary vertices are the flagged ones
    (``flags`` (n,) bool) of the leaves whose box the segment passes within ``snap`` of (a boundary vertex
    is a corner of a face in such a leaf, so a stroke on the whole surface costs what the blade passes,
    not the length of every slit made so far), or, with no flags, the list ``boundary`` (b,) (a stroke's
    patch: a BVH of one leaf, which would read every face). ``positions`` and ``faces``: the corners of
    ``bvh``'s faces in those vertex ids."""
    d = b - a
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    best, best_t = -1, t_max
    if flags.shape[0] == 0:
        for w in boundary:
            best, best_t = _nearer(w, positions, a, d, dd, snap, best, best_t)
        return best, best_t
    node_lo, node_hi, node_left, node_right, node_start, node_count, order, _, _ = bvh
    stack = np.empty(128, np.int64)
    top = 0
    stack[0] = 0
    while top >= 0:
        node = stack[top]
        top -= 1
        if not _near_box(node_lo[node], node_hi[node], a, d, t_max, snap):
            continue
        if node_left[node] >= 0:
            stack, top = _push_children(stack, top, node_left[node], node_right[node])
            continue
        for i in range(node_start[node], node_start[node] + node_count[node]):
            for c in range(3):
                w = faces[order[i], c]
                if flags[w]:
                    best, best_t = _nearer(w, positions, a, d, dd, snap, best, best_t)
    return best, best_t


@helper
def _meet(bvh, positions, faces, flags, boundary, a, b, snap):
    """Where the blade a -> b meets the surface of ``bvh`` (BVHArrays as a tuple), as both a stroke's
    guess and ``_ends`` take it: the first ``boundary`` vertex the blade passes within ``snap`` before
    it hits a face (a slit opened wide ends in a wedge-shaped gap whose tip is a boundary vertex: a
    blade aimed at it, the previous stroke's blade, passes it within rounding and may slip through the
    gap), else the nearest corner of the face hit within ``snap``, else the hit point in the face.
    The boundary vertices: ``flags`` or ``boundary`` (``_boundary_near``); ``positions``, ``faces``: the
    corners of bvh's faces in their vertex ids.

    returns (kind: VERTEX, FACE, or -1 when the blade misses ; id ; point (3,) ; t along the blade ;
    the face hit, -1 at a boundary vertex)
    """
    face, t = _first_hit(bvh, a, b)
    w, t_w = _boundary_near(bvh, positions, faces, flags, boundary, a, b, t if face >= 0 else 1.0, snap)
    if w >= 0:
        return VERTEX, w, positions[w].copy(), t_w, np.int64(-1)
    if face < 0:
        return np.int64(-1), np.int64(-1), np.zeros(3), t, face
    hit = np.empty(3)
    for k in range(3):
        hit[k] = a[k] + t * (b[k] - a[k])
    kind, ident, point = _hit_node(face, hit, faces, positions, snap)
    return kind, ident, point, t, face


@helper
def _plane_through(s0, p, q, tol, min_sine, plane):
    """plane := the plane through s0, p and q when p and q are further than ``tol`` from s0 and not
    aligned with it (the sine between them above ``min_sine``); returns whether it was."""
    u, v = _sub(p, s0), _sub(q, s0)
    lu, lv = _norm(u), _norm(v)
    if lu > tol and lv > tol and _norm(_cross(u, v)) > min_sine * lu * lv:
        r = plane_from_points(s0, p, q)
        plane[0], plane[1], plane[2], plane[3] = r[0], r[1], r[2], r[3]
        return True
    return False


@kernel()
def _ends(bvh, a0, b0, a1, b1, positions, faces, mesh, boundary, tol, min_sine):
    """Steps 2-3: where the blade meets the skin at both times, the tear plane, and the side of
    every welded vertex.

    bvh : BVHArrays (as a tuple) of ``positions`` ; faces : (m, 3) int64
    mesh : WeldedMesh (as a tuple) ; boundary : (b,) int64 welded vertices on a boundary
    tol : absolute snap distance ; min_sine : relative (``tol.min_sine``)
    returns the fields of ``Ends``
    """
    (wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces) = mesh
    ends_int = np.zeros((2, 2), np.int64)
    ends_pos = np.zeros((2, 3))
    hits = np.zeros((2, 3))
    hit_faces = np.full(2, -1, np.int64)
    plane = np.zeros(4)
    cls = np.zeros(wpos.shape[0], np.int8)
    no_flags = np.zeros(0, np.bool_)
    for i in range(2):
        a, b = (a0, b0) if i == 0 else (a1, b1)
        kind, ident, point, t, face = _meet(bvh, wpos, wfaces, no_flags, boundary, a, b, tol)
        if kind < 0:
            return FROM_MISSES + i, ends_int, ends_pos, hits, hit_faces, plane, cls
        for k in range(3):
            hits[i, k] = a[k] + t * (b[k] - a[k])
        hit_faces[i] = face if face >= 0 else vf_faces[vf_offsets[ident]]
        ends_int[i, KIND], ends_int[i, ID] = kind, ident
        _set_row(ends_pos, i, point)
    s0, s1 = ends_pos[0], ends_pos[1]
    if _distance(s1, s0) <= tol:
        return NO_MOTION, ends_int, ends_pos, hits, hit_faces, plane, cls

    # the plane through S_i and the blade at t_{i+1}; fallbacks (module docstring): the blade at t_i
    # (its end further from the line S_i S_{i+1} first), then the mean normal of the hit faces
    hint = np.zeros(3)
    for i in range(2):
        f = hit_faces[i]
        corner = positions[faces[f, 0]]
        normal = _cross(_sub(positions[faces[f, 1]], corner), _sub(positions[faces[f, 2]], corner))
        length = _norm(normal)
        if length > 0.0:
            for k in range(3):
                hint[k] += normal[k] / length
    stroke = _sub(s1, s0)
    far0 = _norm(_cross(stroke, _sub(a0, s0)))
    far1 = _norm(_cross(stroke, _sub(b0, s0)))
    found = False
    for c in range(4):
        if c == 0:
            p, q = a1, b1
        elif c == 1:
            p, q = (s1, a0) if far0 >= far1 else (s1, b0)
        elif c == 2:
            p, q = (s1, b0) if far0 >= far1 else (s1, a0)
        else:
            p, q = s1, np.empty(3)
            for k in range(3):
                q[k] = s0[k] + hint[k] * _norm(stroke)
        if _plane_through(s0, p, q, tol, min_sine, plane):
            found = True
            break
    if not found:
        return NO_PLANE, ends_int, ends_pos, hits, hit_faces, plane, cls

    _classify(plane, wpos, tol, cls)
    for i in range(2):
        if ends_int[i, KIND] == VERTEX:
            cls[ends_int[i, ID]] = 0          # a snapped end is on the plane by definition
    for i in range(2):
        kind, ident, point = _snap_to_edge(
            ends_int[i, KIND], ends_int[i, ID], ends_pos[i], wfaces, face_edges, edges, wpos, cls, plane, tol)
        ends_int[i, KIND], ends_int[i, ID] = kind, ident
        _set_row(ends_pos, i, point)          # may be ends_pos[i] itself: a row copied onto itself
    if ends_int[0, KIND] == ends_int[1, KIND] and ends_int[0, ID] == ends_int[1, ID] and ends_int[0, KIND] != FACE:
        # one vertex, or one crossing; two points of one edge that lies in the plane differ
        e = ends_int[0, ID]
        in_plane = ends_int[0, KIND] == EDGE and cls[edges[e, 0]] == 0 and cls[edges[e, 1]] == 0
        if not in_plane or _distance(ends_pos[0], ends_pos[1]) <= tol:
            return NO_MOTION, ends_int, ends_pos, hits, hit_faces, plane, cls
    return OK, ends_int, ends_pos, hits, hit_faces, plane, cls


def locate(surface, faces, a0, b0, a1, b1, bvh=None) -> Ends:
    """Steps 2-3 on ``surface`` (``surface._Surface``) of the mesh with ``faces`` (m, 3) int64, for
    the blade (handle a, tip b) at t_i (a0, b0) and t_{i+1} (a1, b1), (3,) float64 each; ``bvh`` a
    TriangleBVH of the surface (its own by default)."""
    bvh = surface.bvh if bvh is None else bvh
    return Ends(*_ends(tuple(bvh._arrays), a0, b0, a1, b1, surface.positions, faces, tuple(surface.welded),
                       surface.boundary, tol.snap * surface.diagonal, tol.min_sine))
