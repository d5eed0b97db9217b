"""One tear stroke on a *source* of surface data, as a splice: the rows it changes and the rows it adds.

Both the functional ``tear`` (a rig in, a new rig out) and the editing session ``cgaskin.Surgery``
(mutable arrays kept across strokes) run a stroke through ``stroke_splice``; they differ only in the
source they give it and in what they do with the splice (``stroke.py`` assembles a new rig, the
session writes the rows into its arrays). A source is any object with:

    positions (n, 3) float64   the surface (stored vertices, or skinned in a pose)
    vertices (n, 3), joints (n, 4) int64, weights (n, 4) float64, labels (n,) int64 tear labels
    attributes: dict name -> ((n, c) float64 rows, trailing shape), the tear label excluded
    faces (m, 3) int64         rows that queries do not return may hold anything (removed faces)
    boundary (n,) bool         whether each vertex lies on a boundary edge of the label-aware weld
    top_label int ; diagonal float ; affines (B, 12) float64 or None (rest)
    bvh_arrays                 ``bvh.BVHArrays`` (as a tuple) of a BVH over positions and faces
    check_hits(faces)          raises when the BVH does not hold these faces' triangles (a user's BVH;
                               -1: no face)

The stroke itself is the module docstring of ``stroke.py``, run on the stroke's patch (``patch.py``).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..._shared.jit import F1, F2, I1, I2, f8, helper, i8, kernel, record
from ..._shared.warn import warn
from ...errors import MissesMeshError, PlacementWarning
from ...tolerances import tol
from ..new_vertices import attribute_rule, interpolate_in_place
from ..surface import WELDED_MESH
from ..weld import _boundary_of
from .guess import FOUND, FROM_MISSES, _guess
from .locate import locate
from .region import _margin as _margin_helper
from .patch import patch_surface, select
from .records import JUMP_CARRIER, VERTEX, Pieces, Slit
from .retriangulate import _retriangulate
from .slit import _open_slit, _torn_faces
from .vertex_data import _vertex_data
from .walk import walk


class Splice(NamedTuple):
    """What a stroke changes, in the source's numbering (n vertices, m face rows before it).

    rows : (p,) int64 source vertices of the patch; vertices (p + v, 3), labels (p + v,): those rows
        after the stroke, then the v new vertices (source vertices n, n + 1, ...); joints (p + v, 4),
        weights, attributes {name: (p + v, c)}: the new vertices' rows after p rows that hold only
        what the stroke read (the others are zero: a stroke never changes them)
    changed : (c,) int64 increasing indices into ``rows``: the only rows whose label (the far side's)
        or position (an opening moves the sides apart) the stroke may change
    removed : (a,) int64 faces replaced by pieces ; kept : (k,) int64 the other faces that touch the
        path and kept_corners (k, 3) int64 their corners after the stroke (the far side's use twins)
    pieces : (q, 3) int64 the new faces (source vertex ids), in order ; parents (q,) int64 the removed
        face each lies in
    boundary_rows : (b,) int64 vertices (increasing) whose boundary flag the stroke sets to
        ``boundary_flags`` (b,) bool
    stroke : dict of ``TearResult``'s fields other than ``rig`` (side_a, side_b in source ids)
    """

    rows: np.ndarray
    changed: np.ndarray
    vertices: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    labels: np.ndarray
    attributes: dict
    removed: np.ndarray
    kept: np.ndarray
    kept_corners: np.ndarray
    pieces: np.ndarray
    parents: np.ndarray
    boundary_rows: np.ndarray
    boundary_flags: np.ndarray
    stroke: dict


def _first_guess(source, blades, snap):
    """``guess._guess`` on the source: its plane (None when the points and the blade are aligned: the
    patch then takes every face in the box, and the plane ``locate`` chooses selects it again) and
    margin. Raises MissesMeshError as ``locate`` does."""
    status, plane, margin, hit_faces = _guess(source.bvh_arrays, source.boundary, blades, snap, tol.min_sine)
    source.check_hits(hit_faces)
    if status != FOUND:
        name, i = ("scalpel_from", 0) if status == FROM_MISSES else ("scalpel_to", 2)
        raise MissesMeshError(f"the scalpel {name} (handle {blades[i].tolist()} -> tip {blades[i + 1].tolist()}) "
                              f"does not meet the surface")
    return (plane if plane.any() else None), margin


@kernel((F2, I2, I1, F1, F1), cost=0.1)
def _margin_kernel(wpos, wfaces, hit_faces, s_pos, t_pos):
    return _margin_helper(wpos, wfaces, hit_faces, s_pos, t_pos)


def _margin(surface, ends) -> float:
    """``region._margin`` of the located ends on the patch: |S_(i+1) - S_i| plus the longest edge of
    the two hit faces."""
    return _margin_kernel(surface.welded.positions, surface.welded.faces, ends.hit_faces, ends.points[0],
                          ends.points[1])


def _patch_and_ends(source, blades, check_ends):
    """The stroke's patch and its located ends: the patch of the guessed plane and margin, again with
    the plane and margin ``locate`` found on it until they agree (once, unless the guess was off)."""
    snap = tol.snap * source.diagonal
    plane, margin = _first_guess(source, blades, snap)
    for _ in range(4):
        patch = patch_surface(source, select(source, plane, blades, margin))
        ends = locate(patch.surface, patch.surface.faces, *blades)
        check_ends(ends, patch.surface)
        needed = _margin(patch.surface, ends)
        if plane is not None and ends.plane.tolist() == plane.tolist() and needed <= margin:
            return patch, ends
        plane, margin = ends.plane, max(margin, needed)
    raise AssertionError("the stroke's patch did not settle")      # the plane of a patch is its own


def stroke_splice(source, blades, opening: float, check_ends, no_path) -> Splice:
    """One stroke on ``source``: ``blades`` (4, 3) float64 handle and tip at t_i, then at t_(i+1).

    check_ends(ends, surface) raises the errors of steps 2-3 ; no_path(ends, path) raises when the walk
    found no path (path None) or nothing to tear (no nodes).
    """
    patch, ends = _patch_and_ends(source, blades, check_ends)
    surface, rows = patch.surface, patch.rows
    path = walk(surface, ends, surface.bvh, (blades[0], blades[1]), (blades[2], blades[3]))
    no_path(ends, path)
    p, n = len(rows), len(source.positions)
    pieces, (torn_faces, candidates), slit = _split_along(*path, surface.faces, surface.vertex_welded,
                                                         tuple(surface.welded), p, tol.on_edge, surface.positions,
                                                         ends.plane)
    pieces, slit = Pieces(*pieces), Slit(*slit)
    added = len(pieces.new_node) + len(slit.twins)
    read, changed, vertices, labels, joints, weights = _stroke_rows(
        pieces.new_src, slit.twins, slit.moved, rows, patch.vertices, patch.labels, source.joints, source.weights,
        added)
    posed = source.affines is not None
    residual = _vertex_data(vertices, joints, weights, labels, p, source.top_label, path.points, tuple(pieces),
                            tuple(slit), opening, ends.plane[:3].copy(),
                            source.affines if posed else np.zeros((1, 12)), posed)
    if not residual <= tol.placement * source.diagonal:
        warn(f"a new vertex lands {residual:.3g} from its posed path point when skinned (its "
             f"blended transform is singular or nearly so)", PlacementWarning)
    attributes, twin_of = {}, slit.twins[:, 0].copy()
    for name, (values, _tail) in source.attributes.items():
        values = _gathered(values, rows, read, added)
        # new vertices interpolate their sources, and a twin has its vertex's data
        interpolate_in_place(values, p, pieces.new_src, pieces.new_coef, attribute_rule(name, values.shape[1]),
                             twin_of)
        attributes[name] = values
    boundary_rows, boundary_flags = _boundary_changes(vertices, labels, torn_faces, candidates, surface.vertex_welded,
                                                      len(surface.welded.positions), path.nodes, p)
    removed, kept, kept_corners, new_faces, parents, (side_a, side_b, boundary_rows) = _in_source(
        patch.faces, pieces.affected, pieces.parent, torn_faces, candidates, rows, n,
        (slit.side_a, slit.side_b, boundary_rows))
    stroke = dict(plane=ends.plane, points=path.points[:, 1:4].copy(), kinds=path.nodes[:, 0].copy(),
                  side_a=side_a, side_b=side_b, split=slit.split, hits=ends.hits,
                  jumps=path.nodes[:, 2] == JUMP_CARRIER)
    return Splice(rows, changed, vertices, joints, weights, labels, attributes, removed, kept, kept_corners,
                  new_faces, parents, boundary_rows, boundary_flags, stroke)


@kernel((I2, F2, I2, I1, WELDED_MESH, i8, f8, F2, F1), cost=2.4)
def _split_along(path_int, path_float, faces, vertex_welded, mesh, p, on_edge, positions, plane):
    """Steps 5-6 in one call: the faces the path crosses split (``retriangulate``), the torn faces
    (``slit._torn_faces``) and the slit opened (``slit._open_slit``), on the patch (faces (q, 3) over
    p vertices, vertex_welded (p,), mesh its WeldedMesh as a tuple, positions (p, 3)).

    returns the fields of ``Pieces``, the torn faces and the rows of them around the path, and the
    fields of ``Slit``
    """
    pieces = _retriangulate(path_int, path_float, faces, mesh, p, on_edge)
    torn = _torn_faces(path_int, path_float, faces, vertex_welded, mesh, pieces[0], pieces[1], pieces[2])
    slit = _open_slit(torn[0], torn[1], torn[2], positions, torn[3], plane, torn[4])
    return pieces, (torn[0], torn[4]), slit


@kernel((I1, I1, I1, I2, I1, I1, i8, record(I1, I1, I1)), cost=0.5)
def _in_source(face_ids, affected, parent, torn, candidates, rows, n, vertex_lists):
    """The stroke's faces and vertices in the source's numbering (patch vertex i < p is source
    vertex rows[i], new vertex p + j is n + j; patch face f is face_ids[f]).

    face_ids (q,) ; affected (a,) the patch faces replaced, parent (k,) the index in ``affected`` of
    each piece's face ; torn (q - a + k, 3) the torn faces: the kept ones in order, then the pieces ;
    candidates (c,) rows of ``torn`` around the path ; vertex_lists: patch vertex ids to map
    returns removed (a,), kept (r,) the kept faces among the candidates (the far side's twins can
    reach only those: the others keep their corners) and kept_corners (r, 3), pieces (k, 3), parents
    (k,) the source face of each piece, and the vertex lists mapped
    """
    q, a = face_ids.shape[0], affected.shape[0]
    n_kept = q - a
    kept_ids = np.empty(n_kept, np.int64)         # the patch face of each kept row of ``torn``
    is_affected = np.zeros(q, np.bool_)
    for f in affected:
        is_affected[f] = True
    r = 0
    for f in range(q):
        if not is_affected[f]:
            kept_ids[r] = face_ids[f]
            r += 1
    removed = np.empty(a, np.int64)
    for i in range(a):
        removed[i] = face_ids[affected[i]]
    count = 0
    for c in candidates:
        count += c < n_kept
    kept, kept_corners = np.empty(count, np.int64), np.empty((count, 3), np.int64)
    count = 0
    for c in candidates:
        if c < n_kept:
            kept[count] = kept_ids[c]
            for k in range(3):
                kept_corners[count, k] = _source_vertex(torn[c, k], rows, n)
            count += 1
    k_pieces = torn.shape[0] - n_kept
    pieces, parents = np.empty((k_pieces, 3), np.int64), np.empty(k_pieces, np.int64)
    for i in range(k_pieces):
        for k in range(3):
            pieces[i, k] = _source_vertex(torn[n_kept + i, k], rows, n)
        parents[i] = face_ids[affected[parent[i]]]
    mapped = []
    for vertices in vertex_lists:
        out = np.empty(vertices.shape[0], np.int64)
        for i in range(vertices.shape[0]):
            out[i] = _source_vertex(vertices[i], rows, n)
        mapped.append(out)
    return removed, kept, kept_corners, pieces, parents, (mapped[0], mapped[1], mapped[2])


@helper
def _source_vertex(v, rows, n):
    return rows[v] if v < rows.shape[0] else n + v - rows.shape[0]


@kernel((F2, I1, I2, I1, I1, i8, I2, i8), cost=1.5)
def _boundary_changes(vertices, labels, faces, candidates, welded, n_welded, path_int, p):
    """The patch vertices whose boundary flag a stroke can change -- the copies of the path's vertices
    and the new vertices -- and their flags in the torn patch (welded as ``surface.tear_topology``
    welds: by rest position and label). faces (m, 3) the torn faces, ``candidates`` the rows of them
    that can touch a path node (the pieces and the kept faces around path vertices): the whole fan
    of every vertex asked about. welded (p,) the welded vertex of each patch vertex (of n_welded)."""
    on_path = np.zeros(n_welded, np.bool_)
    for j in range(path_int.shape[0]):
        if path_int[j, 0] == VERTEX:
            on_path[path_int[j, 1]] = True
    changed = np.empty(vertices.shape[0], np.int64)
    count = 0
    for i in range(vertices.shape[0]):
        if i >= p or on_path[welded[i]]:
            changed[count] = i
            count += 1
    changed = changed[:count].copy()
    return changed, _boundary_of(vertices, labels, faces, candidates, changed)


@kernel((I2, I2, I2, I1, F2, I1, I2, F2, i8), cost=0.6)
def _stroke_rows(new_src, twins, moved, rows, vertices, labels, joints, weights, added):
    """The patch's vertex arrays for a stroke, each with ``added`` uninitialised rows after its p rows
    for ``vertex_data`` to fill.

    Of the joints and weights (and, with ``_gathered``, the attributes) only the rows the stroke reads
    are gathered from the source's ``joints``, ``weights`` (n, 4): the new vertices' sources, the
    twins' and the moved rows (a posed opening); the other rows of a large patch would be scattered
    reads of the source that nothing uses (they are zero). ``vertices`` (p, 3), ``labels`` (p,) are
    the patch's own rows (all of them: the boundary is welded from them).
    returns read (increasing patch rows read), changed (increasing: the moved rows, the only ones a
    stroke may change), vertices, labels, joints, weights (p + added rows each)
    """
    p = rows.shape[0]
    is_read, is_changed = np.zeros(p, np.bool_), np.zeros(p, np.bool_)
    for v in new_src.reshape(-1):
        if v < p:
            is_read[v] = True
    for i in range(twins.shape[0]):
        if twins[i, 0] < p:
            is_read[twins[i, 0]] = True
    for i in range(moved.shape[0]):
        if moved[i, 0] < p:
            is_read[moved[i, 0]] = is_changed[moved[i, 0]] = True
    read = np.flatnonzero(is_read)
    out_vertices, out_labels = np.empty((p + added, 3)), np.empty(p + added, np.int64)
    out_vertices[:p], out_labels[:p] = vertices, labels
    return (read, np.flatnonzero(is_changed), out_vertices, out_labels, _gathered(joints, rows, read, added),
            _gathered(weights, rows, read, added))


@kernel((F2, I1, I1, i8), (I2, I1, I1, i8), cost=0.2)
def _gathered(values, rows, read, added):
    """(p + added, c) the rows ``rows[read]`` of ``values`` (n, c) at ``read``, zeros in the other p
    rows, then ``added`` uninitialised rows for a kernel to fill."""
    p = rows.shape[0]
    out = np.empty((p + added, values.shape[1]), values.dtype)
    out[:p] = 0
    for i in read:
        out[i] = values[rows[i]]
    return out
