"""Step 5a of a tear stroke: one crossed face split so that the path's pieces in it become edges
(``retriangulate.py`` splits every crossed face and makes the new vertices)."""
import math

import numpy as np

from ..._shared.jit import helper
from ...algebra.vec3 import _distance
from ...generated.kernels import barycentric
from .records import CARRIER, CARRIER_KIND, EDGE, EDGE_T, FACE, FACE_CARRIER, ID, KIND, POINT, VERTEX


@helper
def _position(code, f, wfaces, wpos, path_float):
    """Position of a polygon element: corner k of face f (code -1-k) or path node ``code``."""
    if code < 0:
        return wpos[wfaces[f, -1 - code]]
    return path_float[code, POINT:POINT + 3]


@helper
def _widest_apex(sub, count, f, wfaces, wpos, path_float):
    """The element of the convex polygon ``sub[:count]`` whose fan has the largest smallest triangle."""
    best, best_area = 0, -1.0
    for p in range(count):
        a = _position(sub[p], f, wfaces, wpos, path_float)
        smallest = np.inf
        for i in range(1, count - 1):
            b = _position(sub[(p + i) % count], f, wfaces, wpos, path_float)
            c = _position(sub[(p + i + 1) % count], f, wfaces, wpos, path_float)
            u0, u1, u2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
            v0, v1, v2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
            area = math.sqrt((u1 * v2 - u2 * v1) ** 2 + (u2 * v0 - u0 * v2) ** 2 + (u0 * v1 - u1 * v0) ** 2)
            smallest = min(smallest, area)
        if smallest > best_area:
            best, best_area = p, smallest
    return best


@helper
def _convex_fan(sub, flat, count, f, wfaces, wpos, path_float, out, n_out):
    """Triangulate a convex polygon (elements ``sub[:count]`` in the face's winding) whose ``flat``
    elements lie inside one of its sides (edge crossings that are not chord ends): a fan from a flat
    element (never collinear with two consecutive others), else the shorter diagonal of a quad, else a
    fan from the first element. Appends to ``out`` from row ``n_out``; returns the new row count."""
    if count < 3:
        return n_out
    p = -1
    for i in range(count):
        if flat[i]:
            p = i
            break
    for i in range(count):
        if flat[i] and flat[(i + 1) % count]:
            # several path nodes on one side (points of an edge that lies in the plane): a fan from a
            # flat element would join collinear ones; fan from the element whose smallest fan triangle
            # is largest (the corner across that side)
            p = _widest_apex(sub, count, f, wfaces, wpos, path_float)
            break
    if p < 0 and count == 4:
        d02 = _distance(_position(sub[0], f, wfaces, wpos, path_float), _position(sub[2], f, wfaces, wpos, path_float))
        d13 = _distance(_position(sub[1], f, wfaces, wpos, path_float), _position(sub[3], f, wfaces, wpos, path_float))
        p = 0 if d02 <= d13 else 1
    if p < 0:
        p = 0
    for i in range(1, count - 1):
        out[n_out, 0], out[n_out, 1], out[n_out, 2] = sub[p], sub[(p + i) % count], sub[(p + i + 1) % count]
        n_out += 1
    return n_out


@helper
def _triangulate_face(f, nodes, path, welded, out, on_edge, work):
    """Split face ``f`` so that the path's pieces in it become edges.

    The face's boundary becomes a polygon: its corners (a path node where the corner is one) with the
    path's edge crossings inserted on their edges. Then: with no path node inside, the chord between
    two boundary elements splits the polygon into two convex pieces (``_convex_fan`` each), or without
    a chord (a face that only shares a crossed edge) a fan from the crossing; with path nodes inside
    (the ends, and the midpoint of a one-segment path), a fan from the one that the chords here share
    over the whole polygon, then each other inside node fanned within the fan triangle that holds it.
    Every piece keeps the face's winding.

    ``nodes`` (increasing) are the path nodes that can concern f (``_face_nodes``): the others are not
    looked at, so that a long path costs what each face holds of it.
    Rows of ``out`` get element codes: -1-k for corner k, j >= 0 for path node j. Returns the row count.
    ``path`` : the fields of ``Path`` ; ``welded`` : the welded mesh's positions, faces, face edges and
    edges (``WeldedMesh``'s first four fields) ; ``work`` : (poly, flat, along, sub, subflat) scratch
    arrays of at least nodes + 3 entries (allocated once per stroke: per face they cost more than the
    face's triangulation)
    """
    path_int, path_float = path
    wpos, wfaces, face_edges, edges = welded
    poly, flat, along, sub, subflat = work          # (every entry below ``count`` is set here)
    count = np.int64(0)
    for k in range(3):
        code = -1 - k
        for j in nodes:
            if path_int[j, KIND] == VERTEX and path_int[j, ID] == wfaces[f, k]:
                code = j
        poly[count], flat[count] = code, False
        count += 1
        first = count
        for j in nodes:
            if path_int[j, KIND] == EDGE and path_int[j, ID] == face_edges[f, k]:
                # in order along the side (several nodes lie on an edge in the plane)
                e = face_edges[f, k]
                s = path_float[j, EDGE_T] if wfaces[f, k] == edges[e, 0] else 1.0 - path_float[j, EDGE_T]
                i = count
                while i > first and along[i - 1] > s:
                    poly[i], along[i] = poly[i - 1], along[i - 1]
                    i -= 1
                poly[i], flat[count], along[i] = j, True, s
                count += 1
    inner = np.empty(3, np.int64)
    n_inner = np.int64(0)
    chord_a, chord_b = -1, -1
    hub_count = np.zeros(3, np.int64)
    for j in nodes:
        if path_int[j, KIND] == FACE and path_int[j, ID] == f:
            inner[n_inner] = j
            n_inner += 1
    for j in nodes:
        if j >= 1 and path_int[j, CARRIER_KIND] == FACE_CARRIER and path_int[j, CARRIER] == f:
            chord_a, chord_b = j - 1, j
            for q in range(n_inner):
                if inner[q] == j - 1 or inner[q] == j:
                    hub_count[q] += 1
    n_out = np.int64(0)
    if n_inner == 0:
        ia, ib = -1, -1
        for i in range(count):
            if poly[i] == chord_a and chord_a >= 0:
                ia = i
            if poly[i] == chord_b and chord_b >= 0:
                ib = i
        gap = (ib - ia) % count if ia >= 0 and ib >= 0 else 0
        if gap < 2 or gap > count - 2:
            return _convex_fan(poly, flat, count, f, wfaces, wpos, path_float, out, np.int64(0))
        for start, stop in ((ia, ib), (ib, ia)):
            size = (stop - start) % count + 1
            for i in range(size):
                sub[i] = poly[(start + i) % count]
                subflat[i] = flat[(start + i) % count] and 0 < i < size - 1
            n_out = _convex_fan(sub, subflat, size, f, wfaces, wpos, path_float, out, n_out)
        return n_out
    # a fan over the whole polygon from an END of the path's segment in this face (the hub), so that
    # the other nodes lie on one ray from it: with three inner nodes (a one-segment path inside the face
    # and its midpoint, collinear) the path's first node; with two (the midpoint, which both chords
    # touch, and one end: the segment's other end is on the boundary) that end, so that the midpoint
    # lies on the fan edge from it to the boundary end and splits it. A fan from the midpoint could
    # put the two ends on adjacent fan edges, whose splits would join all three in a zero-area
    # triangle when the segment runs within rounding of the face's side
    hub = 0
    for q in range(1, n_inner):
        if hub_count[q] < hub_count[hub] and n_inner < 3:
            hub = q
    s = inner[hub]
    for i in range(count):
        out[n_out, 0], out[n_out, 1], out[n_out, 2] = s, poly[i], poly[(i + 1) % count]
        n_out += 1
    # every other inner node goes into the triangle that holds it best (largest smallest
    # barycentric coordinate, generated kernel), fanned there: it is joined to the hub, which is a
    # corner of every fan triangle (the other inner node lies beyond the hub, in another one)
    for q in range(n_inner):
        if q == hub:
            continue
        e = inner[q]
        pe = path_float[e, POINT:POINT + 3]
        best, best_score, best_k = 0, -np.inf, 0
        for i in range(n_out):
            la, lb, lc = barycentric(_position(out[i, 0], f, wfaces, wpos, path_float),
                                     _position(out[i, 1], f, wfaces, wpos, path_float),
                                     _position(out[i, 2], f, wfaces, wpos, path_float), pe)
            score = min(la, min(lb, lc))
            if score > best_score:
                best, best_score = i, score
                best_k = 0 if la == score else (1 if lb == score else 2)
        n_out = _insert_node(out, n_out, best, e, best_score <= on_edge, best_k)
    return n_out


@helper
def _insert_node(out, n_out, t, e, on_edge, k):
    """Insert element ``e`` into triangle row ``t`` of ``out[:n_out]``, keeping the winding: three
    triangles around it, or, when ``on_edge`` (e on the edge opposite corner k), two in ``t`` and two
    in the triangle across that edge (three in ``t`` if no row of ``out`` shares the edge: e then
    lies on the face's own border, which the path's edge crossings cover). Returns the row count."""
    a, b, c = out[t, k], out[t, (k + 1) % 3], out[t, (k + 2) % 3]
    across, x = -1, a
    if on_edge:
        for i in range(n_out):
            for r in range(3):
                if out[i, r] == c and out[i, (r + 1) % 3] == b:
                    across = i
                    x = out[i, (r + 2) % 3]
    if across < 0:
        out[t, 0], out[t, 1], out[t, 2] = e, a, b
        out[n_out, 0], out[n_out, 1], out[n_out, 2] = e, b, c
        out[n_out + 1, 0], out[n_out + 1, 1], out[n_out + 1, 2] = e, c, a
        return n_out + 2
    # e splits edge b-c: (a, b, e), (a, e, c) here and (x, c, e), (x, e, b) across
    out[t, 0], out[t, 1], out[t, 2] = a, b, e
    out[n_out, 0], out[n_out, 1], out[n_out, 2] = a, e, c
    out[across, 0], out[across, 1], out[across, 2] = x, c, e
    out[n_out + 1, 0], out[n_out + 1, 1], out[n_out + 1, 2] = x, e, b
    return n_out + 2
