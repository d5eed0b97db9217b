"""Tear a skinned mesh with a scalpel: a slit along the surface, between two positions of a blade.

``tear(rig, scalpel_from, scalpel_to, pose=None, opening=0.0) -> Rig``

The scalpel is a segment from its handle ``a`` to its tip ``b``; ``scalpel_from = (a0, b0)`` is the
blade at time t_i and ``scalpel_to = (a1, b1)`` at t_{i+1}. Steps (design.md section 4, "Tear"):

1. **Surface.** The stored vertices (``pose=None``), or the skinned positions in ``pose`` (a posed
   tear). Its welded topology (attribute-split copies of a vertex are one, so that the tear crosses
   UV/normal seams) and a BVH over its triangles are built once per rig (and pose) and cached.
2. **Where the blade meets the skin.** S_i is the *first* crossing of segment a0 -> b0 with the
   surface going from the handle a0 towards the tip b0 (the skin the blade enters); S_{i+1} likewise
   for a1 -> b1. The BVH query is two-sided and watertight (``cgaskin.bvh``). A hit within
   ``SNAP_TOLERANCE`` of a mesh vertex is that vertex (this is what lets a stroke that starts where
   the previous one ended continue the same slit), and one within it of where the plane crosses an
   edge of the hit face is that crossing (no zero-area slivers when the blade meets an edge). A
   blade that passes within it of a boundary vertex before its first hit meets the surface there
   (the end of a slit opened wide is the tip of a wedge-shaped gap, which the blade that ended the
   stroke would otherwise slip through by rounding).
3. **Tear plane** through S_i, a1 and b1 (generated ``plane_from_points``): it holds the blade at
   t_{i+1} and both surface points, so the tear runs where the blade swept from S_i to its new
   position. When S_i lies on the line a1 b1 (the blade slid along itself) the plane falls back to
   S_i, S_{i+1} and the blade at t_i (a0 or b0), then to the plane through S_i S_{i+1} that holds the
   mean surface normal of the two hit faces; a stroke with S_i = S_{i+1} raises ``InvalidInputError``.
4. **Path.** The plane cuts the surface in a curve; the path follows it from S_i to S_{i+1} across
   faces (signed distances by the generated ``point_plane_distance``, crossing parameters by
   ``segment_plane``), in both directions at once, and keeps the shorter: a front-propagation over
   the curve that visits each face at most once (so the face count bounds it, with no other step cap)
   and follows the curve through vertices that lie on the plane and along edges that lie in it. A
   curve that never reaches S_{i+1} (the two hits lie on different pieces of the plane's section)
   raises ``TearPathError``.
5. **Re-triangulation.** Every crossed face is split so that the path is a chain of mesh edges: the
   edge crossings and the two end points become new vertices, with weights interpolated (edge: by
   the edge parameter t; inside a face: by its barycentric coordinates from the generated
   ``barycentric``), the 4 largest kept and renormalised, and NORMAL/TEXCOORD_0 (and any other
   attribute) interpolated likewise. Each attribute-split copy of a crossed seam edge gets its own new
   vertex (own UVs), all at one position computed from the welded edge.
6. **Opening the slit.** Each path vertex except the two ends is duplicated: faces on one side of the
   path keep the original copies, faces on the other side get new ones, so the surface is open along
   the path. The two ends stay single (the tear stops inside the surface there: a slit, not a
   hole) -- unless an end lies on an existing boundary (the end of an earlier slit, or a border of an
   open mesh): then it is split too, and the new slit continues the old one. A path of one segment
   (both ends in one face, or on one edge) gets its midpoint as a third vertex, which opens.
   ``opening`` > 0 moves the two sides apart by ±opening/2 along the plane normal (the side the
   normal points to goes +).
7. **Posed tears** place every new vertex in rest space by inverting its blended 3x4 transform,
   so that skinning the torn rig in ``pose`` puts it exactly on the posed path (and the opening
   offset goes through the inverse blended linear part). The copies of one path point share one
   rest position (solved with the first copy's weights), so they stay welded.

Slit copies with opening 0 have the same positions as the copies they were split from, like
attribute-split seam copies. To tell them apart in later strokes, the torn rig carries the per-vertex
attribute ``TEAR_LABEL`` ("_TEAR", (n, 1) float): vertices are welded only when both their positions
and their labels are equal; each stroke gives the far side of its slit a new label. Rigs without it
behave as if it were 0 everywhere. (glTF export writes it as the application attribute "_TEAR".)

The caller's rig is never modified; vertices not on the path keep their index, position, weights and
attributes; faces not crossed keep their corners (the crossed ones are replaced by their pieces at the
end of the face array).
"""
from __future__ import annotations

import math
import warnings
import weakref
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..._shared.checks import float_array
from ..bvh import TriangleBVH, _first_hit
from ...errors import CgaskinError, InvalidInputError, MissesMeshError
from ...generated.kernels import (affine_point, barycentric, plane_from_points, point_plane_distance,
                                segment_plane)
from ...animation.rig import Rig
from ..new_vertices import blend_weight_rows
from ..topology import Topology, incidence, rig_cached, rig_topology, topology

__all__ = ["tear", "tear_stroke", "TearResult", "TearPathError", "TearPlacementWarning", "tear_topology",
           "TEAR_LABEL", "SNAP_TOLERANCE", "PLACEMENT_TOLERANCE"]

#: per-vertex attribute that tells slit copies apart from seam copies (see the module docstring)
TEAR_LABEL = "_TEAR"
#: relative to the surface's bounding-box diagonal: a vertex this close to the tear plane is on it
#: (the path goes through it), and a scalpel hit this close to a vertex is that vertex
SNAP_TOLERANCE = 1e-10
#: relative to the diagonal: a posed tear warns when a new vertex, skinned, misses its path point by more
PLACEMENT_TOLERANCE = 1e-9

# The compiled helpers take these codes (and every other small integer) as np.int64, never as Python
# int literals: numba compiles a separate copy of a helper for each literal value it is called with
# (also for a loop counter that starts at a literal: ``n = 0`` gives one copy for Literal[int](0) and
# one for int64, so such counters start at ``np.int64(0)``).
# Helpers that only other kernels call are compiled with no_cpython_wrapper=True: numba then builds
# no Python entry point for them, which shortens a cold start by about a tenth (cgaskin.precompile).
# path node kinds
VERTEX, EDGE, FACE = np.int64(0), np.int64(1), np.int64(2)
# how a path segment runs from the previous node: across a face, or along an edge in the plane
NO_CARRIER, FACE_CARRIER, EDGE_CARRIER = np.int64(-1), np.int64(0), np.int64(1)


class TearPlacementWarning(UserWarning):
    """A posed tear's new vertex could not be placed exactly on the posed path (its blended
    transform is singular or nearly so)."""


class TearPathError(CgaskinError, ValueError):
    """The tear plane's section of the surface does not lead from S_i to S_{i+1} (they lie on
    different pieces of it, or a boundary of the mesh is in the way)."""


@dataclass(frozen=True, eq=False)
class TearResult:
    """A tear stroke with its bookkeeping.

    rig : Rig, the torn rig
    plane : (4,) float64 dual plane n̂ + d e∞ of the tear, in the surface's space (posed if posed)
    points : (k, 3) float64 path points in the surface's space, S_i first and S_{i+1} last
    kinds : (k,) int64 what each path point is: 0 an existing vertex, 1 an edge crossing, 2 a point
        inside a face (the ends, or the midpoint of a one-segment path)
    side_a, side_b : (k,) int64 one vertex of each path point in the torn rig on the side the plane
        normal points to, and one on the other side (equal where the point was not split: the
        slit's ends inside the surface); other attribute-split copies may exist
    split : (k,) bool, whether the path point was split into two sides
    hits : (2, 3) float64 S_i and S_{i+1} as the scalpel met the surface (before snapping)
    """

    rig: Rig
    plane: np.ndarray
    points: np.ndarray
    kinds: np.ndarray
    side_a: np.ndarray
    side_b: np.ndarray
    split: np.ndarray
    hits: np.ndarray


# ---- the surface: welded topology, positions, BVH (cached) ---------------------------------------------
def _labels(rig) -> np.ndarray:
    """(n,) int64 tear labels of the rig's vertices (0 without the attribute)."""
    values = rig.attributes.get(TEAR_LABEL)
    if values is None:
        return np.zeros(rig.n_vertices, np.int64)
    values = np.asarray(values, dtype=np.float64).reshape(rig.n_vertices, -1)[:, 0]
    if not np.isfinite(values).all():
        raise InvalidInputError(f"attribute {TEAR_LABEL} holds non-finite values")
    return np.rint(values).astype(np.int64)


def _build_tear_topology(rig) -> Topology:
    labels = _labels(rig)
    if not labels.any():
        return rig_topology(rig)
    # weld by position (the shared topology), then split each welded vertex by label: the pair
    # (welded id, label) is numbered through ``topology`` itself, fed with one exact float per pair
    by_position = rig_topology(rig).welded
    key = by_position * (int(labels.max()) + 1) + labels
    keys = np.zeros((rig.n_vertices, 3))
    keys[:, 0] = key.astype(np.float64)        # exact below 2**53
    return topology(keys, rig.faces)


def tear_topology(rig) -> Topology:
    """The welded topology that ``tear`` walks on: vertices are one when their positions and their
    ``TEAR_LABEL`` values are equal (so seams weld and earlier slits stay open). Cached per rig."""
    return rig_cached(rig, "tear.topology", _build_tear_topology)


@dataclass(frozen=True, eq=False)
class _Surface:
    """What one stroke needs of a rig in one pose (rest when posed is None).

    positions : (n, 3) float64 surface positions of every vertex (skinned when posed)
    welded_positions : (w, 3) float64, positions of the welded vertices (their representatives)
    topo : Topology (label-aware, ``tear_topology``)
    vf_offsets, vf_faces : CSR welded vertex -> faces
    bvh : TriangleBVH over ``positions``
    boundary : (b,) int64 welded vertices on a boundary edge (borders, earlier slits)
    diagonal : float, bounding-box diagonal of ``positions``
    affines : (B, 12) bone maps of the pose, or None at rest
    """

    positions: np.ndarray
    welded_positions: np.ndarray
    topo: Topology
    vf_offsets: np.ndarray
    vf_faces: np.ndarray
    bvh: TriangleBVH
    boundary: np.ndarray
    diagonal: float
    affines: np.ndarray | None


def _mesh_checks(rig):
    """Shapes and values the tear relies on, checked once per rig."""
    n = len(rig.vertices)
    vertices = np.asarray(rig.vertices)
    faces = np.asarray(rig.faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.isfinite(vertices).all():
        raise InvalidInputError(f"rig.vertices must be a finite (n, 3) array, got shape {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0 or faces.dtype.kind not in "iu":
        raise InvalidInputError(f"rig.faces must be a non-empty (m, 3) integer array, got {faces.shape}")
    joints, weights = np.asarray(rig.joints), np.asarray(rig.weights)
    if joints.shape != (n, 4) or weights.shape != (n, 4) or joints.dtype.kind not in "iu":
        raise InvalidInputError(f"rig.joints and rig.weights must have shape ({n}, 4), got "
                                f"{joints.shape} and {weights.shape}")
    if not np.isfinite(weights).all() or (weights < 0).any():
        raise InvalidInputError("rig.weights must be finite and >= 0")
    for name, values in rig.attributes.items():
        if len(np.asarray(values)) != n:
            raise InvalidInputError(f"attribute {name!r} has {len(values)} rows for {n} vertices")
    return True


def _build_surface(rig, positions, affines) -> _Surface:
    topo = tear_topology(rig)
    positions = np.ascontiguousarray(positions, dtype=np.float64)
    welded_positions = np.ascontiguousarray(positions[topo.representative])
    vf_offsets, vf_faces, _ = incidence(topo.faces, topo.n_welded)
    bvh = TriangleBVH(positions, rig.faces)
    boundary = np.unique(topo.edges[topo.boundary_edges])
    diagonal = float(np.linalg.norm(positions.max(axis=0) - positions.min(axis=0)))
    return _Surface(positions, welded_positions, topo, vf_offsets, vf_faces, bvh, boundary, diagonal,
                    affines)


# posed surfaces: id(pose) -> (weak reference to the pose, surface), per rig through rig_cached
def _posed_cache(rig) -> dict:
    return rig_cached(rig, "tear.posed", lambda _rig: {})


def _surface(rig, pose) -> _Surface:
    rig_cached(rig, "tear.checks", _mesh_checks)
    if pose is None:
        return rig_cached(rig, "tear.surface", lambda r: _build_surface(r, r.vertices, None))
    from ...animation.pose import check_pose, skin
    check_pose(rig, pose)
    cache = _posed_cache(rig)
    entry = cache.get(id(pose))
    if entry is not None and entry[0]() is pose:
        return entry[1]
    surface = _build_surface(rig, skin(rig, pose), pose.bone_affines())
    if len(cache) > 8:                 # a few poses per rig are plenty: drop the oldest
        cache.pop(next(iter(cache)))
    key = id(pose)
    cache[key] = (weakref.ref(pose, lambda _r, c=cache, k=key: c.pop(k, None)), surface)
    return surface


# ---- the walk along the plane's section -------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy")
def _classify(plane, welded_positions, tol, cls):
    """Side of every welded vertex: +1 / -1, or 0 within ``tol`` of the plane (signed distance up(x)·π
    through the generated kernel). Writes ``cls`` (w,) int8."""
    for w in range(welded_positions.shape[0]):
        d = point_plane_distance(plane, welded_positions[w])
        cls[w] = 0 if abs(d) <= tol else (1 if d > 0.0 else -1)


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _push(ni, nf, target, n, kind, ident, t, x, y, z, parent, carrier_kind, carrier, is_target):
    """Append a node of the search tree; its length is its parent's plus the step."""
    ni[n, 0], ni[n, 1], ni[n, 2], ni[n, 3], ni[n, 4] = kind, ident, parent, carrier_kind, carrier
    nf[n, 0], nf[n, 1], nf[n, 2], nf[n, 3] = t, x, y, z
    step = math.sqrt((x - nf[parent, 1]) ** 2 + (y - nf[parent, 2]) ** 2 + (z - nf[parent, 3]) ** 2)
    nf[n, 4] = nf[parent, 4] + step
    target[n] = is_target
    return n + 1


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy")
def _walk(wpos, wfaces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces, cls, plane,
          s_kind, s_id, s_pos, t_kind, t_id, t_pos):
    """Follow the plane's section of the surface from the start node to the target node.

    Nodes are (kind, id): VERTEX (welded vertex on the plane), EDGE (edge crossed by the plane, at
    its crossing point), FACE (a point inside a face: the start or the target, at s_pos / t_pos);
    the start and the target may be of any kind. The search grows fronts
    from the start along every direction the section leaves it by (two, or more at a saddle), always
    advancing the shortest one, so the first front to pop the target is the shorter way round.
    Each face (and each in-plane edge) is crossed at most once, which bounds the search by the face
    count and keeps fronts from looping.

    returns found (bool), path_int (k, 4) int64 rows (kind, id, carrier kind, carrier id) from start to
    target, where the carrier is what the segment from the previous node runs through (a face, or an
    edge lying in the plane); path_float (k, 4) float64 rows (edge parameter t from edges[id, 0], x, y, z)
    """
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


# ---- re-triangulation of the crossed faces ---------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _position(code, f, wfaces, wpos, path_float):
    """Position of a polygon element: corner k of face f (code -1-k) or path node ``code``."""
    if code < 0:
        return wpos[wfaces[f, -1 - code]]
    return path_float[code, 1:4]


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _triangulate_face(f, path_int, wfaces, face_edges, wpos, path_float, out):
    """Split face ``f`` so that the path's pieces in it become edges.

    The face's boundary becomes a polygon: its corners (a path node where the corner is one) with the
    path's edge crossings inserted on their edges. Then: with no path node inside, the chord between
    two boundary elements splits the polygon into two convex pieces (``_convex_fan`` each), or without
    a chord (a face that only shares a crossed edge) a fan from the crossing; with path nodes inside
    (the ends, and the midpoint of a one-segment path), a fan from the one that the chords here share
    over the whole polygon, then each other inside node fanned within the fan triangle that holds it.
    Every piece keeps the face's winding.

    Rows of ``out`` get element codes: -1-k for corner k, j >= 0 for path node j. Returns the row count.
    """
    k_nodes = path_int.shape[0]
    poly = np.empty(6, np.int64)
    flat = np.zeros(6, np.bool_)
    count = np.int64(0)
    for k in range(3):
        code = -1 - k
        for j in range(k_nodes):
            if path_int[j, 0] == VERTEX and path_int[j, 1] == wfaces[f, k]:
                code = j
        poly[count], flat[count] = code, False
        count += 1
        for j in range(k_nodes):
            if path_int[j, 0] == EDGE and path_int[j, 1] == face_edges[f, k]:
                poly[count], flat[count] = j, True
                count += 1
    inner = np.empty(3, np.int64)
    n_inner = np.int64(0)
    chord_a, chord_b = -1, -1
    hub_count = np.zeros(3, np.int64)
    for j in range(k_nodes):
        if path_int[j, 0] == FACE and path_int[j, 1] == f:
            inner[n_inner] = j
            n_inner += 1
    for j in range(1, k_nodes):
        if path_int[j, 2] == FACE_CARRIER and path_int[j, 3] == f:
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
        sub = np.empty(6, np.int64)
        subflat = np.zeros(6, np.bool_)
        for start, stop in ((ia, ib), (ib, ia)):
            size = (stop - start) % count + 1
            for i in range(size):
                sub[i] = poly[(start + i) % count]
                subflat[i] = flat[(start + i) % count] and 0 < i < size - 1
            n_out = _convex_fan(sub, subflat, size, f, wfaces, wpos, path_float, out, n_out)
        return n_out
    # a fan over the whole polygon from the inner node that every chord here touches (the hub)
    hub = 0
    for q in range(1, n_inner):
        if hub_count[q] > hub_count[hub]:
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
        pe = path_float[e, 1:4]
        best, best_score, best_k = 0, -np.inf, 0
        for i in range(n_out):
            la, lb, lc = barycentric(_position(out[i, 0], f, wfaces, wpos, path_float),
                                     _position(out[i, 1], f, wfaces, wpos, path_float),
                                     _position(out[i, 2], f, wfaces, wpos, path_float), pe)
            score = min(la, min(lb, lc))
            if score > best_score:
                best, best_score = i, score
                best_k = 0 if la == score else (1 if lb == score else 2)
        n_out = _insert_node(out, n_out, best, e, best_score <= ON_EDGE, best_k)
    return n_out


#: a point whose smallest barycentric coordinate in a triangle is at most this lies on the edge
#: opposite that corner (to rounding): splitting the triangle in three there would leave one of zero
#: area, so the edge is split instead
ON_EDGE = 1e-9


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _add_unique(values, count, value):
    """Append ``value`` to ``values[:count]`` unless it is there (short lists); grows the array."""
    for q in range(count):
        if values[q] == value:
            return values, count
    if count == values.shape[0]:
        values = np.concatenate((values, np.empty_like(values)))
    values[count] = value
    return values, count + 1


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _new_vertex(code, f, path_int, path_float, faces, wfaces, face_edges, edges, wpos, new_node, new_src,
                new_coef, n_new):
    """The new vertex of path node ``code`` as face ``f`` uses it: found among the first ``n_new`` or
    appended. An edge crossing has one per attribute-split copy of its edge (the pair of vertex ids
    of the face's corners there), with coefficients (1 - s, s) by the edge parameter from the face's
    own corner; a point inside the face has one, with its barycentric coordinates (generated
    kernel). returns (index among the new vertices, new count)."""
    if path_int[code, 0] == EDGE:
        e = path_int[code, 1]
        k = 0
        while face_edges[f, k] != e:
            k += 1
        va, vb = faces[f, k], faces[f, (k + 1) % 3]
        for q in range(n_new):
            if new_node[q] == code and ((new_src[q, 0] == va and new_src[q, 1] == vb)
                                        or (new_src[q, 0] == vb and new_src[q, 1] == va)):
                return q, n_new
        s = path_float[code, 0] if wfaces[f, k] == edges[e, 0] else 1.0 - path_float[code, 0]
        new_src[n_new, 0], new_src[n_new, 1], new_src[n_new, 2] = va, vb, va
        new_coef[n_new, 0], new_coef[n_new, 1], new_coef[n_new, 2] = 1.0 - s, s, 0.0
    else:
        for q in range(n_new):
            if new_node[q] == code:
                return q, n_new
        la, lb, lc = barycentric(wpos[wfaces[f, 0]], wpos[wfaces[f, 1]], wpos[wfaces[f, 2]],
                                 path_float[code, 1:4])
        if not (math.isfinite(la) and math.isfinite(lb) and math.isfinite(lc)):
            # a face of zero area (the file's, or a sliver): its longest side is all there is of it
            la, lb, lc = _segment_coordinates(wpos[wfaces[f, 0]], wpos[wfaces[f, 1]], wpos[wfaces[f, 2]],
                                              path_float[code, 1:4])
        # a point on the face's boundary may come out a rounding error outside
        la, lb, lc = max(la, 0.0), max(lb, 0.0), max(lc, 0.0)
        total = la + lb + lc
        new_src[n_new, 0], new_src[n_new, 1], new_src[n_new, 2] = faces[f, 0], faces[f, 1], faces[f, 2]
        new_coef[n_new, 0], new_coef[n_new, 1], new_coef[n_new, 2] = la / total, lb / total, lc / total
    new_node[n_new] = code
    return n_new, n_new + 1


@njit(cache=True, nogil=True, error_model="numpy")
def _retriangulate(path_int, path_float, faces, wfaces, face_edges, edges, ef_offsets, ef_faces, wpos,
                   n_vertices):
    """Split every face the path crosses (and every face on a crossed edge) and create the new vertices.

    returns
        affected (a,) int64 faces replaced by their pieces
        tris (q, 3) int64 the pieces, as vertex ids of the torn mesh (new vertices from ``n_vertices``)
        new_node (v,) int64 path node of each new vertex
        new_src (v, 3) int64, new_coef (v, 3) float64: each new vertex interpolates the data of the
            vertices new_src with coefficients new_coef (``_new_vertex``)
    """
    k_nodes = path_int.shape[0]
    affected = np.empty(4 * k_nodes + 8, np.int64)
    n_aff = np.int64(0)
    for j in range(k_nodes):
        if path_int[j, 2] == FACE_CARRIER:
            affected, n_aff = _add_unique(affected, n_aff, path_int[j, 3])
        if path_int[j, 0] == FACE:
            affected, n_aff = _add_unique(affected, n_aff, path_int[j, 1])
        if path_int[j, 0] == EDGE:
            e = path_int[j, 1]
            for r in range(ef_offsets[e], ef_offsets[e + 1]):
                affected, n_aff = _add_unique(affected, n_aff, ef_faces[r])
    affected = affected[:n_aff]

    tris = np.empty((12 * n_aff, 3), np.int64)
    n_tris = np.int64(0)
    new_node = np.empty(4 * k_nodes + 4, np.int64)
    new_src = np.zeros((4 * k_nodes + 4, 3), np.int64)
    new_coef = np.zeros((4 * k_nodes + 4, 3))
    n_new = np.int64(0)
    local = np.empty((16, 3), np.int64)
    for a in range(n_aff):
        f = affected[a]
        n_local = _triangulate_face(f, path_int, wfaces, face_edges, wpos, path_float, local)
        for i in range(n_local):
            for c in range(3):
                code = local[i, c]
                if code < 0:                                   # a corner of the face
                    tris[n_tris, c] = faces[f, -1 - code]
                elif path_int[code, 0] == VERTEX:              # a corner that is on the path
                    k = 0
                    while wfaces[f, k] != path_int[code, 1]:
                        k += 1
                    tris[n_tris, c] = faces[f, k]
                else:                                          # a new vertex
                    if n_new + 1 >= new_node.shape[0]:
                        new_node = np.concatenate((new_node, np.empty_like(new_node)))
                        new_src = np.concatenate((new_src, np.zeros_like(new_src)))
                        new_coef = np.concatenate((new_coef, np.zeros_like(new_coef)))
                    vid, n_new = _new_vertex(code, f, path_int, path_float, faces, wfaces, face_edges, edges,
                                             wpos, new_node, new_src, new_coef, n_new)
                    tris[n_tris, c] = n_vertices + vid
            n_tris += 1
    return (affected, tris[:n_tris].copy(), new_node[:n_new].copy(), new_src[:n_new].copy(),
            new_coef[:n_new].copy())


# ---- opening the slit ------------------------------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _append_row(rows, count, a, b, c, d):
    """rows[count, :4] = (a, b, c, d) (columns beyond the array's width dropped), growing the
    array when full; returns (rows, count + 1)."""
    if count == rows.shape[0]:
        rows = np.concatenate((rows, np.empty_like(rows)))
    rows[count, 0], rows[count, 1], rows[count, 2], rows[count, 3] = a, b, c, d
    return rows, count + 1


@njit(cache=True, nogil=True, error_model="numpy")
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
    The groups of all split nodes, joined the same way, form the two sides of the slit; the side
    whose faces lie furthest along the plane normal (summed signed distances of their centroids) keeps
    the original vertices, the other gets copies ("twins"), one per attribute-split copy it uses. A
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


# ---- data of the new vertices -------------------------------------------------------------------------
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _blended(joints, weights, affines, i):
    """(12,) the blended row-major 3x4 map Σ_k w_k A[joints[i, k]] of vertex i."""
    out = np.zeros(12)
    for s in range(4):
        w = weights[i, s]
        if w != 0.0:
            a = affines[joints[i, s]]
            for c in range(12):
                out[c] += w * a[c]
    return out


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _solve_linear(m, r):
    """x with L x = r for the linear part L of a row-major 3x4 map ``m`` (Cramer's rule); NaN if L
    is singular."""
    a, b, c = m[0], m[1], m[2]
    d, e, f = m[4], m[5], m[6]
    g, h, i = m[8], m[9], m[10]
    c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
    det = a * c0 + b * c1 + c * c2
    out = np.empty(3)
    if det == 0.0:
        out[:] = np.nan
        return out
    out[0] = (r[0] * c0 + r[1] * (c * h - b * i) + r[2] * (b * f - c * e)) / det
    out[1] = (r[0] * c1 + r[1] * (a * i - c * g) + r[2] * (c * d - a * f)) / det
    out[2] = (r[0] * c2 + r[1] * (b * g - a * h) + r[2] * (a * e - b * d)) / det
    return out


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _to_rest(target, guess, blend):
    """The rest position x whose blended map ``blend`` (12,) puts it at ``target`` (3,): solved
    relative to ``guess`` (the interpolated rest position, close to the answer) and refined once on
    the residual (generated ``affine_point``), so the error is that of one map evaluation.
    returns x (3,), residual |blend(x) - target| (inf when the map is singular: x stays the guess)"""
    x = guess.copy()
    r = np.empty(3)
    for _ in range(2):
        y = affine_point(blend, x)
        r[0], r[1], r[2] = target[0] - y[0], target[1] - y[1], target[2] - y[2]
        dx = _solve_linear(blend, r)
        if not (math.isfinite(dx[0]) and math.isfinite(dx[1]) and math.isfinite(dx[2])):
            return x, np.inf
        x += dx
    y = affine_point(blend, x)
    return x, math.sqrt((target[0] - y[0]) ** 2 + (target[1] - y[1]) ** 2 + (target[2] - y[2]) ** 2)


@njit(cache=True, nogil=True, error_model="numpy")
def _rows(out, n, src, coef, twin_src, unit):
    """An attribute extended to the torn mesh, in place: ``out`` (n + v + t, c) float64 holds the
    original rows in its first n; the new vertices' rows interpolate their sources (Σ_r coef[i, r] ·
    out[src[i, r]], renormalised to unit length when ``unit``: normals), the twins' rows copy their
    vertex's."""
    c = out.shape[1]
    v, t = src.shape[0], twin_src.shape[0]
    for i in range(v):
        for q in range(c):
            out[n + i, q] = (coef[i, 0] * out[src[i, 0], q] + coef[i, 1] * out[src[i, 1], q]
                             + coef[i, 2] * out[src[i, 2], q])
        if unit:
            length = 0.0
            for q in range(c):
                length += out[n + i, q] ** 2
            if length > 0.0:
                length = math.sqrt(length)
                for q in range(c):
                    out[n + i, q] /= length
    for i in range(t):
        _copy_row(out, n + v + i, out, twin_src[i])


# ---- the stroke, in compiled steps ------------------------------------------------------------------
# status codes of ``_ends``
OK, FROM_MISSES, TO_MISSES, NO_MOTION, NO_PLANE = 0, 1, 2, 3, 4
#: below this sine, three points are too close to one line to define the tear plane's normal
MIN_SINE = 1e-6


# 3-vector helpers: scalar loops, because numba compiles every array expression (``a - b``,
# ``np.sum(x ** 2)``) into a kernel of its own, a fraction of a second of compile time each
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _cross(u, v):
    out = np.empty(3)
    out[0] = u[1] * v[2] - u[2] * v[1]
    out[1] = u[2] * v[0] - u[0] * v[2]
    out[2] = u[0] * v[1] - u[1] * v[0]
    return out


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _sub(p, q):
    """p - q (3,)"""
    out = np.empty(3)
    for k in range(3):
        out[k] = p[k] - q[k]
    return out


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _norm(u):
    return math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _distance(p, q):
    """|p - q| of two (3,) points"""
    return math.sqrt((p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2)


# Rows are copied by loops: numba's array-into-array assignment (``dst[i] = src``) compiles its
# shape-mismatch message (string formatting), seconds of compile time in every process.
@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _set_row(dst, i, src):
    """dst[i] = src (c,)"""
    for c in range(src.shape[0]):
        dst[i, c] = src[c]


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _copy_row(dst, i, src, j):
    """dst[i] = src[j] (no view of the row: this runs for every vertex)"""
    for c in range(src.shape[1]):
        dst[i, c] = src[j, c]


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
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


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _snap_to_edge(kind, ident, point, wfaces, face_edges, edges, wpos, cls, plane, tol):
    """A point inside a face within ``tol`` of where the plane crosses one of the face's edges is that
    crossing (an EDGE node), so that a scalpel through an edge splits both faces on it instead of
    leaving a zero-area sliver."""
    if kind != FACE:
        return kind, ident, point
    for k in range(3):
        if cls[wfaces[ident, k]] * cls[wfaces[ident, (k + 1) % 3]] < 0:
            e = face_edges[ident, k]
            t, x, y, z = segment_plane(plane, wpos[edges[e, 0]], wpos[edges[e, 1]])
            if math.sqrt((x - point[0]) ** 2 + (y - point[1]) ** 2 + (z - point[2]) ** 2) <= tol:
                crossing = np.empty(3)
                crossing[0], crossing[1], crossing[2] = x, y, z
                return EDGE, e, crossing
    return kind, ident, point


@njit(cache=True, nogil=True, error_model="numpy", no_cpython_wrapper=True)
def _boundary_hit(a, b, t_max, boundary, wpos, tol):
    """The first boundary vertex within ``tol`` of segment a -> b before parameter ``t_max``:
    (welded vertex, t) or (-1, t_max). A slit opened wide ends in a wedge-shaped gap whose tip is the
    slit's end vertex: a blade aimed at that vertex (the previous stroke's blade, to continue the
    slit) passes it within rounding and may slip through the gap, so it counts as meeting it."""
    d = _sub(b, a)
    dd = _dot(d, d)
    best, best_t = -1, t_max
    for w in boundary:
        p = wpos[w]
        t = min(max(((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / dd, 0.0), 1.0)
        if t < best_t and math.sqrt((a[0] + t * d[0] - p[0]) ** 2 + (a[1] + t * d[1] - p[1]) ** 2
                                    + (a[2] + t * d[2] - p[2]) ** 2) <= tol:
            best, best_t = w, t
    return best, best_t


@njit(cache=True, nogil=True, error_model="numpy")
def _ends(lo, hi, left, right, start, count, order, tri, a0, b0, a1, b1, positions, faces, wpos,
          wfaces, face_edges, edges, vf_offsets, vf_faces, boundary, tol):
    """Steps 2-3: where the blade meets the skin at both times, the tear plane, and the side of
    every welded vertex.

    returns status (OK or why not), ends_int (2, 2) (kind, id) of S_i and S_{i+1}, ends_pos (2, 3),
    hits (2, 3) the raw scalpel hits, hit_faces (2,), plane (4,), cls (w,) int8
    """
    ends_int = np.zeros((2, 2), np.int64)
    ends_pos = np.zeros((2, 3))
    hits = np.zeros((2, 3))
    hit_faces = np.full(2, -1, np.int64)
    plane = np.zeros(4)
    cls = np.zeros(wpos.shape[0], np.int8)
    for i in range(2):
        a, b = (a0, b0) if i == 0 else (a1, b1)
        face, t = _first_hit(lo, hi, left, right, start, count, order, tri, a, b)
        w, t_w = _boundary_hit(a, b, t if face >= 0 else 1.0, boundary, wpos, tol)
        if w >= 0:
            for k in range(3):
                hits[i, k] = a[k] + t_w * (b[k] - a[k])
            hit_faces[i] = vf_faces[vf_offsets[w]]
            ends_int[i, 0], ends_int[i, 1] = VERTEX, w
            _set_row(ends_pos, i, wpos[w])
            continue
        if face < 0:
            return FROM_MISSES + i, ends_int, ends_pos, hits, hit_faces, plane, cls
        for k in range(3):
            hits[i, k] = a[k] + t * (b[k] - a[k])
        hit_faces[i] = face
        kind, ident, point = _hit_node(face, hits[i], wfaces, wpos, tol)
        ends_int[i, 0], ends_int[i, 1] = kind, ident
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
        u, v = _sub(p, s0), _sub(q, s0)
        lu, lv = _norm(u), _norm(v)
        if lu > tol and lv > tol and _norm(_cross(u, v)) > MIN_SINE * lu * lv:
            r = plane_from_points(s0, p, q)
            plane[0], plane[1], plane[2], plane[3] = r[0], r[1], r[2], r[3]
            found = True
            break
    if not found:
        return NO_PLANE, ends_int, ends_pos, hits, hit_faces, plane, cls

    _classify(plane, wpos, tol, cls)
    for i in range(2):
        if ends_int[i, 0] == VERTEX:
            cls[ends_int[i, 1]] = 0          # a snapped end is on the plane by definition
    for i in range(2):
        kind, ident, point = _snap_to_edge(
            ends_int[i, 0], ends_int[i, 1], ends_pos[i], wfaces, face_edges, edges, wpos, cls, plane, tol)
        ends_int[i, 0], ends_int[i, 1] = kind, ident
        _set_row(ends_pos, i, point)          # may be ends_pos[i] itself: a row copied onto itself
    if ends_int[0, 0] == ends_int[1, 0] and ends_int[0, 1] == ends_int[1, 1] and ends_int[0, 0] != FACE:
        return NO_MOTION, ends_int, ends_pos, hits, hit_faces, plane, cls
    return OK, ends_int, ends_pos, hits, hit_faces, plane, cls


@njit(cache=True, nogil=True, error_model="numpy")
def _torn_faces(path_int, path_float, faces, welded, wfaces, affected, tris, new_node, vf_offsets, vf_faces,
                n_welded):
    """The faces of the torn mesh, with what ``_open_slit`` needs.

    affected, tris, new_node : from ``_retriangulate``
    returns torn (m', 3) int64 (the kept faces in order, then the pieces), torn_w (m', 3) int64 their
    welded corners (new vertex i is welded n_welded + its path node), node_w (k,) int64 the welded
    vertex of each path node, new_positions (v, 3) float64, candidates (c,) int64 sorted rows of
    ``torn`` that may touch a path node
    """
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
        node_w[j] = path_int[j, 1] if path_int[j, 0] == VERTEX else n_welded + j
    new_positions = np.empty((new_node.shape[0], 3))
    for i in range(new_node.shape[0]):
        for c in range(3):
            new_positions[i, c] = path_float[new_node[i], 1 + c]
    # the faces that can touch a path node, in increasing order: the kept faces around path vertices,
    # and the pieces (the last rows)
    is_candidate = np.zeros(m_out, np.bool_)
    for j in range(k_nodes):
        if path_int[j, 0] == VERTEX:
            w = path_int[j, 1]
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


@njit(cache=True, nogil=True, error_model="numpy")
def _vertex_data(out_v, out_j, out_w, out_l, n, path_float, new_node, new_src, new_coef, twins, moved, opening,
                 normal, affines, posed):
    """Step 7 and the vertex arrays of the torn mesh: originals, new vertices, twins.

    New vertices get interpolated weights (``_blend_weights``) and, at rest, their path point as
    position; in a pose, one rest position per path node, solved with the node's first copy's
    weights, so that all copies of a node (one per attribute-split copy of a seam edge) keep one
    position and stay welded even where their weights differ a little. Twins copy their vertex. The
    far side of the slit gets the new tear label (``labels.max() + 1`` + rank). With ``opening`` > 0
    the near side moves by +opening/2 along ``normal`` and the far side by -opening/2: in a pose, the
    offset goes through the inverse blended linear part of the node's first copy on that side (again
    one offset per node and side, for the same reason).

    out_v (N, 3) float64, out_j (N, 4) int64, out_w (N, 4) float64, out_l (N,) int64 with N = n + v + t:
        the vertex arrays of the torn mesh, the originals in their first n rows (the caller copies
        them: numpy's copy beats a compiled loop); filled here
    twins (t, 3), moved (s, 4): as ``_open_slit`` returns them
    returns the largest placement residual |skinned new vertex - its posed path point| (0 at rest)
    """
    v, t = new_node.shape[0], twins.shape[0]
    new_joints, new_weights = blend_weight_rows(new_src, new_coef, out_j, out_w)
    top = 0
    for i in range(n):
        top = max(top, out_l[i])
    k_nodes = path_float.shape[0]
    first = np.full(k_nodes, -1, np.int64)
    residual = 0.0
    for i in range(v):
        _copy_row(out_j, n + i, new_joints, i)
        _copy_row(out_w, n + i, new_weights, i)
        out_l[n + i] = max(out_l[new_src[i, 0]], max(out_l[new_src[i, 1]], out_l[new_src[i, 2]]))
        j = new_node[i]
        if not posed:
            for c in range(3):
                out_v[n + i, c] = path_float[j, 1 + c]
        elif first[j] >= 0:
            _copy_row(out_v, n + i, out_v, n + first[j])
        else:
            first[j] = i
            guess = np.empty(3)
            for c in range(3):
                guess[c] = (new_coef[i, 0] * out_v[new_src[i, 0], c] + new_coef[i, 1] * out_v[new_src[i, 1], c]
                            + new_coef[i, 2] * out_v[new_src[i, 2], c])
            blend = _blended(new_joints, new_weights, affines, i)
            x, res = _to_rest(path_float[j, 1:4], guess, blend)
            _set_row(out_v, n + i, x)
            if not res <= residual:          # NaN too: a residual that is not a number is reported
                residual = res
    for i in range(t):
        _copy_row(out_v, n + v + i, out_v, twins[i, 0])
        _copy_row(out_j, n + v + i, out_j, twins[i, 0])
        _copy_row(out_w, n + v + i, out_w, twins[i, 0])
        out_l[n + v + i] = top + 1 + twins[i, 1]
    for i in range(moved.shape[0]):
        if moved[i, 1] < 0:
            out_l[moved[i, 0]] = top + 1 + moved[i, 2]
    if opening > 0.0:
        # (vertex, sign, node) of every vertex of a split node; offsets per (node, side)
        k = moved.shape[0] + t
        ids = np.empty(k, np.int64)
        signs = np.empty(k)
        nodes = np.empty(k, np.int64)
        for i in range(moved.shape[0]):
            ids[i], signs[i], nodes[i] = moved[i, 0], moved[i, 1], moved[i, 3]
        for i in range(t):
            q = moved.shape[0] + i
            ids[q], signs[q], nodes[q] = n + v + i, -1.0, twins[i, 2]
        offset = np.empty((k_nodes, 2, 3))
        done = np.zeros((k_nodes, 2), np.bool_)
        delta = np.empty(3)
        for i in range(k):
            side = 0 if signs[i] > 0 else 1
            j = nodes[i]
            if not done[j, side]:
                done[j, side] = True
                for c in range(3):
                    delta[c] = signs[i] * (0.5 * opening * normal[c])
                if posed:
                    delta = _solve_linear(_blended(out_j, out_w, affines, ids[i]), delta)
                for c in range(3):
                    offset[j, side, c] = delta[c]
        for i in range(k):
            for c in range(3):
                out_v[ids[i], c] += offset[nodes[i], 0 if signs[i] > 0 else 1, c]
    return residual


def _scalpel(value, name):
    """(a, b) handle and tip, (3,) float64 each, from a (2, 3) pair."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = float_array(value, name)          # raises with the reason
    if arr.shape == (2, 3) and not np.isfinite(arr).all():
        float_array(arr, name)                  # raises, naming the bad entry
    if arr.shape != (2, 3):
        raise InvalidInputError(f"{name} must be a pair of points (handle a, tip b), shape (2, 3), "
                                f"got shape {arr.shape}")
    if np.array_equal(arr[0], arr[1]):
        raise InvalidInputError(f"{name}: the handle and the tip coincide at {arr[0].tolist()}; the "
                                f"scalpel must be a segment of non-zero length")
    return arr[0], arr[1]


def _opening(value) -> float:
    try:
        opening = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"opening must be a number >= 0, got {value!r}") from None
    if not math.isfinite(opening) or opening < 0:
        raise InvalidInputError(f"opening must be a finite number >= 0, got {value!r}")
    return opening


def _insert_midpoint(path_int, path_float, welded_positions, edges):
    """A one-segment path gets its midpoint as a third node, so that the slit has a vertex to split
    (with both ends kept single, a single edge could not open)."""
    kind, carrier = path_int[1, 2], path_int[1, 3]
    p0, p1 = path_float[0, 1:4], path_float[1, 1:4]
    if kind == FACE_CARRIER:
        mid_int = [FACE, carrier, FACE_CARRIER, carrier]
        mid_float = [0.0, *(0.5 * (p0 + p1))]
    else:                                      # along an edge in the plane: its midpoint
        lo, hi = welded_positions[edges[carrier]]
        mid_int = [EDGE, carrier, EDGE_CARRIER, carrier]
        mid_float = [0.5, *(0.5 * (lo + hi))]
    return (np.array([path_int[0], mid_int, path_int[1]], np.int64),
            np.array([path_float[0], mid_float, path_float[1]]))


def tear_stroke(rig: Rig, scalpel_from, scalpel_to, pose=None, opening: float = 0.0,
                bvh: TriangleBVH | None = None) -> TearResult:
    """One scalpel stroke, with its bookkeeping (``tear`` returns only the rig).

    Parameters
    ----------
    rig : Rig
    scalpel_from, scalpel_to : (2, 3) float
        The blade (handle a, tip b) at t_i and at t_{i+1}.
    pose : Pose, optional
        Tear the mesh as skinned in this pose (default: the stored bind-pose vertices
        ``rig.vertices``). What a viewer shows at rest is ``skin(rig)``; where that differs from
        the stored mesh (bind matrices that are not the rest pose's, e.g. a mesh node with an
        offset), pass ``pose=rig.rest_pose()`` to tear what it shows.
    opening : float >= 0
        Distance the two sides of the slit are moved apart, along the tear plane's normal (in the
        pose's space for a posed tear).
    bvh : TriangleBVH, optional
        A BVH of the surface being torn (``TriangleBVH(rig.vertices, rig.faces)``, or of the skinned
        positions in ``pose``); by default one is built on first use and cached per rig and pose.

    Returns
    -------
    TearResult

    Raises
    ------
    MissesMeshError
        A scalpel segment does not meet the surface (the message names which).
    TearPathError
        The plane's section of the surface does not lead from S_i to S_{i+1}.
    InvalidInputError
        Wrong shapes, non-finite values, a negative opening, a zero-length blade, a stroke that does
        not move across the surface, a pose of another skeleton, a BVH of other positions.
    """
    if not isinstance(rig, Rig):
        raise InvalidInputError(f"rig must be a cgaskin.Rig, got {type(rig).__name__}")
    a0, b0 = _scalpel(scalpel_from, "scalpel_from")
    a1, b1 = _scalpel(scalpel_to, "scalpel_to")
    opening = _opening(opening)
    surface = _surface(rig, pose)
    if bvh is None:
        bvh = surface.bvh
    elif not isinstance(bvh, TriangleBVH) or bvh.n_faces != rig.n_faces:
        raise InvalidInputError(f"bvh must be a TriangleBVH over the rig's {rig.n_faces} faces")
    topo = surface.topo
    wpos = surface.welded_positions
    tol = SNAP_TOLERANCE * surface.diagonal
    faces = np.asarray(rig.faces)

    # 2-3: where the blade meets the skin at both times, the tear plane, the sides of the vertices
    status, ends_int, ends_pos, hits, hit_faces, plane, cls = _ends(
        *bvh._arrays, a0, b0, a1, b1, surface.positions, faces, wpos, topo.faces, topo.face_edges,
        topo.edges, surface.vf_offsets, surface.vf_faces, surface.boundary, tol)
    if status in (FROM_MISSES, TO_MISSES):
        name, (a, b) = ("scalpel_from", (a0, b0)) if status == FROM_MISSES else ("scalpel_to", (a1, b1))
        raise MissesMeshError(f"the scalpel {name} (handle {a.tolist()} -> tip {b.tolist()}) does not "
                              f"meet the surface")
    if bvh is not surface.bvh:
        for f in hit_faces[hit_faces >= 0]:
            if not np.array_equal(bvh.triangle(f), surface.positions[faces[f]]):
                raise InvalidInputError("bvh was built from other positions than the surface being torn "
                                        "(the stored vertices, or the skinned positions in the given pose)")
    if status == NO_MOTION:
        raise InvalidInputError(f"the stroke does not move across the surface: the scalpel meets it at "
                                f"the same point {ends_pos[0].tolist()} at both times (nothing to tear)")
    if status == NO_PLANE:
        raise InvalidInputError("cannot place a tear plane: the scalpel at both times and the surface "
                                "normal are all aligned with the stroke from S_i to S_{i+1}")
    (s_kind, s_id), (t_kind, t_id) = ends_int
    s_pos, t_pos = ends_pos

    # 4: the path
    if s_kind == FACE and t_kind == FACE and s_id == t_id:
        path_int = np.array([[FACE, s_id, NO_CARRIER, -1], [FACE, s_id, FACE_CARRIER, s_id]], np.int64)
        path_float = np.array([[0.0, *s_pos], [0.0, *t_pos]])
    else:
        found, path_int, path_float = _walk(
            wpos, topo.faces, topo.face_edges, topo.edges, topo.edge_face_offsets, topo.edge_face_faces,
            surface.vf_offsets, surface.vf_faces, cls, plane, s_kind, s_id, s_pos, t_kind, t_id, t_pos)
        if not found:
            raise TearPathError(
                f"the tear plane's section of the surface, followed from S_i = {s_pos.tolist()}, does "
                f"not reach S_(i+1) = {t_pos.tolist()}: the two points lie on different pieces of the "
                f"section, or a boundary of the mesh is in the way (use shorter strokes)")
    if len(path_int) == 2:
        path_int, path_float = _insert_midpoint(path_int, path_float, wpos, topo.edges)

    # 5-6: re-triangulate, open the slit (separate kernels, so that a cold start compiles them in
    # parallel: cgaskin.precompile)
    affected, tris, new_node, new_src, new_coef = _retriangulate(
        path_int, path_float, faces, topo.faces, topo.face_edges, topo.edges, topo.edge_face_offsets,
        topo.edge_face_faces, wpos, rig.n_vertices)
    torn_faces, torn_w, node_w, new_positions, candidates = _torn_faces(
        path_int, path_float, faces, topo.welded, topo.faces, affected, tris, new_node, surface.vf_offsets,
        surface.vf_faces, len(wpos))
    split, twins, moved, side_a, side_b = _open_slit(
        torn_faces, torn_w, node_w, surface.positions, new_positions, plane, candidates)

    # 7: the vertex data
    mesh = rig_cached(rig, "tear.arrays", _arrays)
    posed = pose is not None
    affines = surface.affines if posed else np.zeros((1, 12))
    n, added = rig.n_vertices, len(new_node) + len(twins)
    vertices, joints, weights, labels = (_extended(values, added) for values in mesh[:4])
    residual = _vertex_data(vertices, joints, weights, labels, n, path_float, new_node, new_src, new_coef,
                            twins, moved, opening, plane[:3].copy(), affines, posed)
    if not residual <= PLACEMENT_TOLERANCE * surface.diagonal:
        warnings.warn(f"a new vertex lands {residual:.3g} from its posed path point when skinned (its "
                      f"blended transform is singular or nearly so)", TearPlacementWarning, stacklevel=2)
    attributes = {}
    for name, (values, tail) in mesh[4].items():
        rows = _extended(values, added)
        _rows(rows, n, new_src, new_coef, twins[:, 0].copy(), name == "NORMAL")
        attributes[name] = rows.reshape((len(rows),) + tail)
    if split.any() or TEAR_LABEL in rig.attributes:
        attributes[TEAR_LABEL] = labels[:, None].astype(np.float64)

    torn = rig.with_mesh(vertices, torn_faces, joints, weights, attributes)
    return TearResult(rig=torn, plane=plane, points=path_float[:, 1:4].copy(), kinds=path_int[:, 0].copy(),
                      side_a=side_a, side_b=side_b, split=split, hits=hits)


def _extended(values, rows: int) -> np.ndarray:
    """``values`` (n, ...) followed by ``rows`` uninitialised rows, for a kernel to fill."""
    out = np.empty((len(values) + rows,) + values.shape[1:], values.dtype)
    out[:len(values)] = values
    return out


def _arrays(rig):
    """The rig's arrays as the kernels take them (float64/int64, C-contiguous; attributes as ((n, c)
    float64, their original trailing shape), without the tear label), converted once per rig."""
    attributes = {}
    for name, values in rig.attributes.items():
        if name != TEAR_LABEL:
            values = np.asarray(values, dtype=np.float64)
            attributes[name] = (np.ascontiguousarray(values.reshape(len(values), -1)), values.shape[1:])
    return (np.ascontiguousarray(rig.vertices, dtype=np.float64),
            np.ascontiguousarray(rig.joints, dtype=np.int64),
            np.ascontiguousarray(rig.weights, dtype=np.float64), _labels(rig), attributes)


def tear(rig: Rig, scalpel_from, scalpel_to, pose=None, opening: float = 0.0,
         bvh: TriangleBVH | None = None) -> Rig:
    """Tear ``rig`` along the surface between two positions of a scalpel; returns the torn rig.

    scalpel_from, scalpel_to : (2, 3) the blade (handle a, tip b) at t_i and at t_{i+1}
    pose : Pose or None (tear the skinned surface in that pose; default the stored vertices
        ``rig.vertices``; ``rig.rest_pose()`` tears what a viewer shows at rest)
    opening : float >= 0, how far apart the two sides of the slit are moved
    bvh : optional TriangleBVH of the surface (built and cached per rig and pose otherwise)

    See the module docstring for the algorithm and ``tear_stroke`` for the errors and a variant that
    also returns the path. Tearing the result again from where this stroke ended continues the slit.
    """
    return tear_stroke(rig, scalpel_from, scalpel_to, pose=pose, opening=opening, bvh=bvh).rig
