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
    tip int                    the vertex at the tip of the slit the last stroke made (-1: none; ``tip.py``)
    bvh_arrays                 ``bvh.BVHArrays`` (as a tuple) of a BVH over positions and faces
    check_hits(faces)          raises when the BVH does not hold these faces' triangles (a user's BVH;
                               -1: no face)

The stroke itself is the module docstring of ``stroke.py``, run on the stroke's patch (``patch.py``,
``settle.py``): steps 2-7 are one compiled call (``_stroke``), then the attributes' rows one call each.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..._shared.jit import F1, F2, I1, I2, callee, f8, helper, i8, kernel, record
from ..._shared.warn import warn
from ...errors import InternalError, MissesMeshError, PlacementWarning
from ...tolerances import tol
from ..new_vertices import attribute_rule, interpolate_in_place
from ..posed_bounds import POSING, _pose_blades
from ..weld import _boundary_of
from .guess import _guess
from .opening import _opening_offsets
from .records import (CARRIER_KIND, FROM_MISSES, ID, JUMP_CARRIER, KIND, MOVED_VERTEX, OK, POINT, TWIN_OF, VERTEX,
                      Ends, Path, StrokeSource, Tolerances)
from .retriangulate import _retriangulate
from .settle import PATCH_ARRAYS, STROKE_SOURCE, _settle
from .slit import _open_slit, _torn_faces
from .tip import _onto_tip
from .vertex_data import _vertex_data
from .walk import _walk


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
    removed: np.ndarray
    kept: np.ndarray
    kept_corners: np.ndarray
    pieces: np.ndarray
    parents: np.ndarray
    boundary_rows: np.ndarray
    boundary_flags: np.ndarray
    attributes: dict
    stroke: dict


def stroke_splice(source, blades, opening: float, check_ends, no_path) -> Splice:
    """One stroke on ``source``: ``blades`` (4, 3) float64 handle and tip at t_i, then at t_(i+1).

    check_ends(ends) raises the errors of steps 2-3 ; no_path(ends, path) raises when the walk
    found no path (path None) or nothing to tear (no nodes). Raises MissesMeshError when a scalpel
    position misses the surface.
    """
    tolerances = Tolerances(tol.snap, tol.min_sine, tol.on_edge)
    status, hit_faces, located = _stroke(tuple(stroke_source(source)), blades, tuple(tolerances), opening,
                                         source.posing, source.tip, max(opening, tol.tip_reach * source.diagonal))
    source.check_hits(hit_faces)
    if status != OK:
        name, i = ("scalpel_from", 0) if status == FROM_MISSES else ("scalpel_to", 2)
        raise MissesMeshError(f"the scalpel {name} (handle {blades[i].tolist()} -> tip {blades[i + 1].tolist()}) "
                              f"does not meet the surface")
    settled, ends, (found, nodes, points), spliced = located
    ends = Ends(*ends)
    check_ends(ends)
    if not settled:
        # (the plane located on a patch is its own, so the patch settles in the second round)
        raise InternalError(f"the stroke's patch did not settle: this is a bug in cgaskin, not bad input; please "
                            f"report it with the model and the scalpel positions {blades.tolist()}")
    no_path(ends, Path(nodes, points) if found else None)
    rows, ((new_src, new_coef, twin_of, read), arrays, (points, kinds, side_a, side_b, split, jumps),
           residual) = spliced
    if not residual <= tol.placement * source.diagonal:
        warn(f"a new vertex lands {residual:.3g} from its posed path point when skinned (its "
             f"blended transform is singular or nearly so)", PlacementWarning)
    # new vertices interpolate their sources, and a twin has its vertex's data
    attributes = {name: _attribute_rows(values, rows, read, new_src, new_coef, attribute_rule(name, values.shape[1]),
                                        twin_of) for name, (values, _tail) in source.attributes.items()}
    stroke = dict(plane=ends.plane, points=points, kinds=kinds, side_a=side_a, side_b=side_b, split=split,
                  hits=ends.hits, jumps=jumps)
    return Splice(rows, *arrays, attributes, stroke)


def stroke_source(source) -> StrokeSource:
    """A source's arrays and values as the compiled stroke takes them (``affines`` zeros at rest)."""
    posed = source.affines is not None
    return StrokeSource(source.bvh_arrays, source.boundary, source.vertices, source.positions, source.labels,
                        source.faces, source.joints, source.weights, source.affines if posed else np.zeros((1, 12)),
                        posed, source.top_label, source.diagonal)


@kernel((STROKE_SOURCE, F2, record(f8, f8, f8), f8, POSING, i8, f8), cost=13.0, fused=True)
def _stroke(source, blades, tolerances, opening, posing, tip, reach):
    """Steps 2-7 of one stroke on a source's arrays (``records.StrokeSource``; ``tolerances`` a
    ``records.Tolerances``, relative), compiled in one call: every step hands the next a dozen arrays,
    and from Python each returned array cost a boxing and each step a call (half a small mesh's
    stroke). ``posing`` (``posed_bounds.Posing``), when active, poses the parts of the rest tree and
    mesh each query reaches first (the source's ``bvh`` is then the posed tree it fills). A blade at
    t_i that passes within ``reach`` of vertex ``tip``, the tip of the slit the last stroke made (-1:
    none), is moved onto it first (``tip.py``): the stroke continues that slit.

    returns the guess's status (``records.OK``, or which scalpel position missed) and hit faces (2,),
    then None when it missed, else (settled, the fields of ``Ends``, (found, the fields of ``Path``),
    the splice): the splice is None unless the patch settled and the walk found a path with nodes, else
    (rows (p,), ``_splice_arrays``' values as a tuple)
    """
    bvh, boundary, _, _, _, _, _, _, _, _, _, diagonal = source
    snap, min_sine, on_edge = tolerances
    snap = snap * diagonal
    blades = _onto_tip(source, blades, tip, reach, snap)
    _pose_blades(bvh, posing, blades, 2.0 * snap)      # the guess's queries stay within snap of the blades
    status, plane, margin, hit_faces = _guess(bvh, boundary, blades, snap, min_sine)
    located = None
    if status == OK:
        settled, patch, tree, ends = _settle(source, blades, plane, plane.any(), margin, snap, min_sine, posing)
        _, rows, patch_faces, patch_positions, _, mesh, _, _, _ = patch
        _, ends_int, ends_pos, _, ends_faces, ends_plane, sides = ends
        found, path_int, path_float = False, np.empty((0, 4), np.int64), np.empty((0, 4))
        spliced = None
        if settled:
            found, path_int, path_float = _walk(
                mesh, sides, ends_plane, (ends_int[0, KIND], ends_int[0, ID], ends_pos[0]),
                (ends_int[1, KIND], ends_int[1, ID], ends_pos[1]), tree + (patch_positions, patch_faces),
                (blades[0], blades[1], blades[2], blades[3]), ends_faces, snap)
            if found and path_int.shape[0] > 0:
                spliced = (rows, _splice_arrays((path_int, path_float), patch, ends_plane, source, on_edge, opening))
        located = (settled, ends, (found, path_int, path_float), spliced)
    return status, hit_faces, located


@callee((record(I2, F2), PATCH_ARRAYS, F1, STROKE_SOURCE, f8, f8), cost=22.0)
def _splice_arrays(path, patch, plane, source, on_edge, opening):
    """Steps 5-7 on the patch and the splice in the source's numbering: the faces the path
    crosses split (``retriangulate``), the torn faces and the slit opened (``slit.py``), the vertex rows
    (``vertex_data``), the boundary flags that change, all mapped to the source (``_in_source``).

    path : the ``Path``'s fields ; patch : ``records.PatchArrays`` ; plane (4,) the tear plane ;
    source : ``records.StrokeSource`` (its joints, weights, affines and top label) ;
    returns (new_src, new_coef, twin_of, read) for the attributes (``_attribute_rows``), the fields
    of ``Splice`` from ``changed`` to ``boundary_flags``, (points, kinds, side_a, side_b, split,
    jumps) of the stroke's record, and the largest placement residual (``vertex_data``)
    """
    path_int, path_float = path
    face_ids, rows, faces, positions, vertex_welded, mesh, _, vertices, labels = patch
    _, _, _, source_positions, _, _, joints, weights, affines, posed, top_label, _ = source
    n = source_positions.shape[0]
    p = rows.shape[0]
    pieces = _retriangulate(path_int, path_float, faces, mesh, p, on_edge)
    affected, _, new_node, new_src, new_coef, parent = pieces
    torn_faces, torn_welded, node_welded, new_positions, candidates = _torn_faces(
        path_int, path_float, faces, vertex_welded, mesh, affected, pieces[1], new_node)
    slit = _open_slit(torn_faces, torn_welded, node_welded, positions, new_positions, plane, candidates)
    split, twins, moved, side_a, side_b = slit
    offsets = _opening_offsets(torn_faces, candidates, positions, new_positions, plane, slit, opening)
    added = new_node.shape[0] + twins.shape[0]
    read, changed, out_vertices, out_labels, out_joints, out_weights = _stroke_rows(
        new_src, twins, moved, rows, vertices, labels, joints, weights, added)
    residual = _vertex_data((out_vertices, out_joints, out_weights, out_labels), p, top_label, path_float, pieces,
                            slit, (opening, plane[:3].copy(), offsets), affines, posed)
    boundary_rows, boundary_flags = _boundary_changes(out_vertices, out_labels, torn_faces, candidates, vertex_welded,
                                                      mesh[0].shape[0], path_int, p)
    removed, kept, kept_corners, new_faces, parents, (side_a, side_b, boundary_rows) = _in_source(
        face_ids, affected, parent, torn_faces, candidates, rows, n, (side_a, side_b, boundary_rows))
    k_nodes = path_int.shape[0]
    points, kinds, jumps = np.empty((k_nodes, 3)), np.empty(k_nodes, np.int64), np.empty(k_nodes, np.bool_)
    for i in range(k_nodes):
        points[i] = path_float[i, POINT:POINT + 3]
        kinds[i], jumps[i] = path_int[i, KIND], path_int[i, CARRIER_KIND] == JUMP_CARRIER
    return ((new_src, new_coef, twins[:, TWIN_OF].copy(), read),
            (changed, out_vertices, out_joints, out_weights, out_labels, removed, kept, kept_corners, new_faces,
             parents, boundary_rows, boundary_flags),
            (points, kinds, side_a, side_b, split, jumps), residual)


@kernel((F2, I1, I1, I2, F2, i8, I1), cost=0.5)
def _attribute_rows(values, rows, read, new_src, new_coef, rule, twin_of):
    """An attribute's splice rows: ``values`` (n, c) gathered at ``rows[read]`` (``_gathered``), then
    the new vertices' rows interpolated by ``rule`` and the twins' copied from ``twin_of``."""
    out = _gathered(values, rows, read, new_src.shape[0] + twin_of.shape[0])
    interpolate_in_place(out, rows.shape[0], new_src, new_coef, rule, twin_of)
    return out


@helper
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


@helper
def _boundary_changes(vertices, labels, faces, candidates, welded, n_welded, path_int, p):
    """The patch vertices whose boundary flag a stroke can change -- the copies of the path's vertices
    and the new vertices -- and their flags in the torn patch (welded as ``surface.tear_topology``
    welds: by rest position and label). faces (m, 3) the torn faces, ``candidates`` the rows of them
    that can touch a path node (the pieces and the kept faces around path vertices): the whole fan
    of every vertex asked about. welded (p,) the welded vertex of each patch vertex (of n_welded)."""
    on_path = np.zeros(n_welded, np.bool_)
    for j in range(path_int.shape[0]):
        if path_int[j, KIND] == VERTEX:
            on_path[path_int[j, ID]] = True
    changed = np.empty(vertices.shape[0], np.int64)
    count = 0
    for i in range(vertices.shape[0]):
        if i >= p or on_path[welded[i]]:
            changed[count] = i
            count += 1
    changed = changed[:count].copy()
    return changed, _boundary_of(vertices, labels, faces, candidates, changed)


@helper
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
        if twins[i, TWIN_OF] < p:
            is_read[twins[i, TWIN_OF]] = True
    for i in range(moved.shape[0]):
        if moved[i, MOVED_VERTEX] < p:
            is_read[moved[i, MOVED_VERTEX]] = is_changed[moved[i, MOVED_VERTEX]] = True
    read = np.flatnonzero(is_read)
    out_vertices, out_labels = np.empty((p + added, 3)), np.empty(p + added, np.int64)
    out_vertices[:p], out_labels[:p] = vertices, labels
    return (read, np.flatnonzero(is_changed), out_vertices, out_labels, _gathered(joints, rows, read, added),
            _gathered(weights, rows, read, added))


@helper
def _gathered(values, rows, read, added):
    """(p + added, c) the rows ``rows[read]`` of ``values`` (n, c) at ``read``, zeros in the other p
    rows, then ``added`` uninitialised rows for a kernel to fill."""
    p = rows.shape[0]
    out = np.empty((p + added, values.shape[1]), values.dtype)
    out[:p] = 0
    for i in read:
        out[i] = values[rows[i]]
    return out
