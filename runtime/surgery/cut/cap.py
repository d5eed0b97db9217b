"""Step 7 of a cut: planar caps over the loops the cut opened (ear clipping, holes bridged in)."""
import math

import numpy as np

from ..._shared.jit import F2, I1, f8, helper, kernel
from ...animation.rig import Rig
from ...tolerances import tol
from ..loops import directed_loops
from ..topology import Topology, topology
from .result import CAP_VERTEX


@helper
def _orient(ax, ay, bx, by, cx, cy):
    """Twice the signed area of triangle abc (> 0: counter-clockwise)."""
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@helper
def _is_ear(xy, ids, nxt, p, i, q, min_sine):
    """Whether corner i (between p and q) of the remaining polygon can be clipped: convex by more
    than rounding (sine of its turn > ``min_sine``: a run of collinear loop vertices, where the plane
    meets a flat part of the mesh, would otherwise be fanned into zero-area triangles), and no other
    remaining vertex inside or on the triangle (vertices that repeat one of its three, as bridge
    endpoints do, are ignored)."""
    ax, ay = xy[p, 0], xy[p, 1]
    bx, by = xy[i, 0], xy[i, 1]
    cx, cy = xy[q, 0], xy[q, 1]
    turn = _orient(ax, ay, bx, by, cx, cy)
    if turn <= min_sine * math.sqrt(((bx - ax) ** 2 + (by - ay) ** 2) * ((cx - bx) ** 2 + (cy - by) ** 2)):
        return False
    v = nxt[q]
    while v != p:
        if ids[v] != ids[p] and ids[v] != ids[i] and ids[v] != ids[q]:
            px, py = xy[v, 0], xy[v, 1]
            if (_left_or_on(ax, ay, bx, by, px, py, min_sine) and _left_or_on(bx, by, cx, cy, px, py, min_sine)
                    and _left_or_on(cx, cy, ax, ay, px, py, min_sine)):
                return False
        v = nxt[v]
    return True


@helper
def _left_or_on(ax, ay, bx, by, px, py, min_sine):
    """Whether p lies left of the line a -> b or on it, up to rounding (the sine of the angle at a
    between b and p at most ``min_sine`` to the right): a loop vertex that the plane's section puts on
    a triangle's side, where the plane runs along a flat part of the mesh, is on it even when its 2D
    coordinates put it a rounding error outside (clipping that ear would leave a zero-area triangle)."""
    turn = _orient(ax, ay, bx, by, px, py)
    return turn >= 0.0 or turn >= -min_sine * math.sqrt(((bx - ax) ** 2 + (by - ay) ** 2)
                                                        * ((px - ax) ** 2 + (py - ay) ** 2))


@kernel((F2, I1, f8), cost=0.5)
def _ear_clip(xy, ids, min_sine):
    """Triangulate a counter-clockwise simple polygon (possibly weakly simple: holes bridged in, with
    repeated vertices) by ear clipping.

    xy : (k, 2) float64 vertices in order ; ids : (k,) int64 vertex identities (repeats share one)
    returns (k - 2, 3) int64 counter-clockwise triangles of polygon positions
    """
    k = xy.shape[0]
    tris = np.empty((max(k - 2, 0), 3), np.int64)
    if k < 3:
        return tris
    prev = np.empty(k, np.int64)
    nxt = np.empty(k, np.int64)
    for j in range(k):
        prev[j] = (j - 1) % k
        nxt[j] = (j + 1) % k
    remaining = k
    count = 0
    i = np.int64(0)
    misses = 0
    while remaining > 3:
        p = prev[i]
        q = nxt[i]
        if _is_ear(xy, ids, nxt, p, i, q, min_sine):
            pass
        elif misses > remaining:
            # A full turn without an ear: the polygon is degenerate here (collinear or touching
            # vertices from float rounding). Clip the most convex corner to make progress.
            best, best_area, j = i, -np.inf, i
            for _ in range(remaining):
                a = _orient(xy[prev[j], 0], xy[prev[j], 1], xy[j, 0], xy[j, 1], xy[nxt[j], 0], xy[nxt[j], 1])
                if a > best_area:
                    best, best_area = j, a
                j = nxt[j]
            i, p, q = best, prev[best], nxt[best]
        else:
            i = q
            misses += 1
            continue
        tris[count, 0] = p
        tris[count, 1] = i
        tris[count, 2] = q
        count += 1
        nxt[p] = q
        prev[q] = p
        remaining -= 1
        misses = 0
        i = q
    tris[count, 0] = prev[i]
    tris[count, 1] = i
    tris[count, 2] = nxt[i]
    return tris


def _signed_area(xy) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(x @ np.roll(y, -1) - y @ np.roll(x, -1))


def _inside(point, xy) -> bool:
    """Even-odd rule: whether ``point`` (2,) is inside the closed polygon ``xy`` (k, 2)."""
    a, b = xy, np.roll(xy, -1, axis=0)
    crosses = (a[:, 1] > point[1]) != (b[:, 1] > point[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (point[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(crosses & (x > point[0])) % 2)


def _bridge(polygon: list, hole: list, xy) -> list:
    """Splice ``hole`` (clockwise) into ``polygon`` (counter-clockwise), both lists of ids indexing
    ``xy``, through a bridge from the hole's rightmost vertex M to a polygon vertex visible from it
    (Eberly, "Triangulation by ear clipping", section 3)."""
    h = int(np.argmax(xy[hole, 0]))
    mx, my = xy[hole[h]]
    ring = np.asarray(polygon)
    a, b = xy[ring], xy[np.roll(ring, -1)]
    crosses = (a[:, 1] > my) != (b[:, 1] > my)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (my - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    hits = np.flatnonzero(crosses & (x >= mx))
    if len(hits) == 0:
        return None
    e = int(hits[np.argmin(x[hits])])
    ix = float(x[e])
    j = e if a[e, 0] >= b[e, 0] else (e + 1) % len(ring)     # the hit edge's end further along +x
    px, py = xy[ring[j]]
    # polygon vertices inside the triangle M, I, P would hide P: take the one closest in angle to +x
    q = xy[ring]
    s1 = _orient_np(mx, my, ix, my, q[:, 0], q[:, 1])
    s2 = _orient_np(ix, my, px, py, q[:, 0], q[:, 1])
    s3 = _orient_np(px, py, mx, my, q[:, 0], q[:, 1])
    sense = np.sign(_orient_np(mx, my, ix, my, px, py)) or 1.0
    inside = (sense * s1 > 0) & (sense * s2 > 0) & (sense * s3 > 0) & (q[:, 0] > mx)
    if inside.any():
        cand = np.flatnonzero(inside)
        dx, dy = q[cand, 0] - mx, np.abs(q[cand, 1] - my)
        j = int(cand[np.lexsort((dx, dy / dx))[0]])
    return polygon[:j + 1] + hole[h:] + hole[:h + 1] + polygon[j:]


def _orient_np(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


def _cap_triangles(loops: list, xy) -> np.ndarray:
    """Triangles (t, 3) over the loops' vertex ids, covering the region the loops bound.

    loops : list of lists of ids into ``xy`` (w, 2), oriented as the cap must run along them: outer
        loops counter-clockwise, holes clockwise (what a consistently oriented closed mesh gives)
    returns (t, 3) int64, counter-clockwise where the loops are.

    Nesting comes from the orientation, not from even-odd counting: each hole is bridged into the
    smallest outer loop around it (so a hollow ball's cap is an annulus, and an island inside a hole
    is an outer loop of its own), while outer loops that overlap (sections of a self-intersecting mesh,
    such as interpenetrating fingers) get overlapping caps of their own instead of cancelling. A hole
    with no outer loop around it (possible only on an open or inconsistently oriented mesh) is capped
    on its own, keeping its orientation.
    """
    polys = [np.asarray(loop, np.int64) for loop in loops if len(loop) >= 3]
    areas = [_signed_area(xy[p]) for p in polys]
    outers = {i: [] for i in range(len(polys)) if areas[i] > 0}
    lone_holes = []
    for i in range(len(polys)):
        if areas[i] > 0:
            continue
        # a probe point: the midpoint of the hole's longest edge (its vertices may touch the outer loop)
        a, b = xy[polys[i]], xy[np.roll(polys[i], -1)]
        e = int(np.argmax(np.sum((b - a) ** 2, axis=1)))
        probe = 0.5 * (a[e] + b[e])
        around = [o for o in outers if _inside(probe, xy[polys[o]])]
        if around:
            outers[min(around, key=lambda o: areas[o])].append(i)
        else:
            lone_holes.append(i)
    triangles = [np.empty((0, 3), np.int64)]
    for o, holes in outers.items():
        polygon = list(polys[o])
        for hole in sorted(holes, key=lambda i: -xy[polys[i], 0].max()):
            merged = _bridge(polygon, list(polys[hole]), xy)
            if merged is None:
                lone_holes.append(hole)
            else:
                polygon = merged
        ids = np.asarray(polygon, np.int64)
        triangles.append(ids[_ear_clip(np.ascontiguousarray(xy[ids]), ids, tol.collinear_sine)])
    for hole in lone_holes:
        ids = polys[hole][::-1]
        triangles.append(ids[_ear_clip(np.ascontiguousarray(xy[ids]), ids, tol.collinear_sine)][:, ::-1])
    return np.concatenate(triangles)


def _plane_basis(normal):
    """Unit u, v with u × v = normal (unit)."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def _cap(half: Rig, sources, cut_positions, plane, on_plane_input, original: Topology, outward: float,
         affines):
    """Close ``half`` over the loops the cut opened; returns the capped rig and its sources.

    cut_positions : (n, 3) the half's vertices in the space that was cut (posed for a posed cut)
    on_plane_input : (n_input,) bool, the input vertices the cut classified as on the plane
    outward : -1 for the positive half (its caps face -n), +1 for the negative half

    Which vertices are on the plane comes from the cut's own bookkeeping (its new vertices, and the
    input vertices it classified so), not from distances recomputed here: far from the origin those
    lose the precision that tells a vertex on the plane from one beside it (no cap at 1e10). The
    loops are triangulated in coordinates relative to the section for the same reason.
    """
    # The cut's loops run along edges whose two ends are on the plane, and every face on such an edge
    # has both ends as corners: the welded topology of the faces with two or more corners on the plane
    # has the same boundary edges there as the whole half's, and is much smaller.
    on_vertex = np.ones(len(half.vertices), bool)          # new vertices lie on the plane
    kept = sources >= 0
    on_vertex[kept] = on_plane_input[sources[kept]]
    near = half.faces[np.count_nonzero(on_vertex[half.faces], axis=1) >= 2]
    if len(near) == 0:
        return half, sources
    used, sub_faces = np.unique(near, return_inverse=True)
    ht = topology(half.vertices[used], sub_faces.reshape(-1, 3))
    rep = used[ht.representative]                 # the half's vertex for each welded sub-vertex
    on = on_vertex[rep]
    be = ht.boundary_edges
    inc = ht.edge_face_offsets[be]
    f, k = ht.edge_face_faces[inc], ht.edge_face_corners[inc].astype(np.int64)
    start, end = ht.faces[f, k], ht.faces[f, (k + 1) % 3]
    keep = on[start] & on[end]
    # an edge between two input vertices that was already a boundary edge of the input is not a cut
    src_a, src_b = sources[rep[start]], sources[rep[end]]
    both = np.flatnonzero(keep & (src_a >= 0) & (src_b >= 0))
    if len(both):
        e = original.find_edges(original.welded[src_a[both]], original.welded[src_b[both]])
        was_boundary = (e >= 0) & (original.edge_face_counts[np.maximum(e, 0)] == 1)
        keep[both[was_boundary]] = False
    start, end = start[keep], end[keep]
    if len(start) == 0:
        return half, sources
    normal = outward * plane[:3]
    u, v = _plane_basis(normal)
    loop_welded = np.unique(np.concatenate([start, end]))
    local = np.full(ht.n_welded, -1, np.int64)
    local[loop_welded] = np.arange(len(loop_welded))
    p = cut_positions[rep[loop_welded]]
    p = p - p.mean(axis=0)                      # relative to the section: exact differences far out
    xy = np.stack([p @ u, p @ v], axis=1)
    # A cap runs along each loop against its faces' direction, so it continues their orientation:
    # chain the reversed edges. Where loops touch at a vertex (the plane through a saddle vertex),
    # the sharpest left turn keeps each loop around its own region (the region lies to the left).
    rs, re = local[end], local[start]

    def sharpest_left(previous, vertex, candidates):
        back = xy[previous] - xy[vertex]
        out = xy[re[candidates]] - xy[vertex]
        clockwise = np.mod(np.arctan2(back[1], back[0]) - np.arctan2(out[:, 1], out[:, 0]), 2 * np.pi)
        return int(np.argmin(np.where(clockwise > 0, clockwise, 2 * np.pi)))

    loops = directed_loops(rs, re, choose=sharpest_left)
    triangles = _cap_triangles(loops, xy)
    if len(triangles) == 0:
        return half, sources

    # cap vertices: one per loop vertex that a cap triangle uses (chains that did not close have none)
    kept, triangles = np.unique(triangles, return_inverse=True)
    triangles = triangles.reshape(-1, 3)
    xy = xy[kept]
    row = rep[loop_welded[kept]]                 # the half's vertex each cap vertex copies
    attributes = {}
    for key, values in half.attributes.items():
        values = np.asarray(values)
        extra = values[row].astype(np.float64)
        if key == "NORMAL" and values.shape[1:] == (3,):
            extra = _cap_normals(half, row, normal, affines)
        elif key.startswith("TEXCOORD") and values.shape[1:] == (2,):
            extent = max(float(np.ptp(xy[:, 0])), float(np.ptp(xy[:, 1])), 1e-300)
            extra = (xy - xy.min(axis=0)) / extent        # planar projection, aspect kept
        attributes[key] = np.concatenate([values, extra.astype(values.dtype, copy=False)])
    capped = half._with_checked_mesh(np.concatenate([half.vertices, half.vertices[row]]),
                                    np.concatenate([half.faces, triangles + half.n_vertices]),
                                    np.concatenate([half.joints, half.joints[row]]),
                                    np.concatenate([half.weights, half.weights[row]]), attributes)
    return capped, np.concatenate([sources, np.full(len(row), CAP_VERTEX, np.int64)])


def _cap_normals(half, rows, normal, affines):
    """Rest-space normals of cap vertices that skin to ``normal``: normals map by the cofactor of the
    blended linear part L, so the rest normal is L^T n (normalised); in a rest cut, n itself."""
    if affines is None:
        return np.tile(normal, (len(rows), 1))
    blend = np.einsum("vk,vkc->vc", half.weights[rows], affines[half.joints[rows]]).reshape(-1, 3, 4)
    out = np.einsum("vji,j->vi", blend[:, :, :3], normal)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.divide(out, length, out=np.tile(normal, (len(rows), 1)), where=length > 0)
