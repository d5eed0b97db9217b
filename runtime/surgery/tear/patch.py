"""The part of the surface one stroke can reach, as a surface of its own.

A stroke's path runs along the tear plane's section of the surface, within ``margin`` of the region
the blade swept (``region.py``). Every face the walk can visit touches the plane (a corner within the
snap distance of it, or corners on both sides) and touches the region; so do the faces around every
path vertex (they share a vertex that lies on the plane), every face on a crossed edge, and the faces
a jump across an opening crosses. The *patch* is the faces that come within ``delta`` (twice the snap
distance) of the plane inside the region's bounding box widened by the margin: a few hundred faces on a
mesh of millions. Its own welded topology, BVH and boundary are built per stroke, so that a stroke
costs what it touches; what the patch cannot know by itself comes from the whole surface: which
vertices lie on a boundary (``source.boundary``; a patch's outer rim is not one), the bounding-box
diagonal that scales the tolerances, and the highest tear label.

Faces outside the patch never matter: an edge between a patch face and another face lies on one side
of the plane beyond the snap distance (or outside the box), so the walk can neither cross it nor
stand on it, and no boundary vertex outside the patch lies on the plane inside the region.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..._shared.jit import helper, kernel
from ..bvh import TriangleBVH, _faces_near_plane, _tree
from ..surface import WeldedMesh, _Surface
from ..topology import _corner_pairs, _unique_pairs, incidence
from ..weld import _weld_positions
from .records import PatchArrays


_EPS = float(np.finfo(np.float64).eps)
#: patches of at most this many faces get a BVH of one leaf (a stroke queries it a few times)
ONE_LEAF = 4096


class Patch(NamedTuple):
    """A stroke's part of the surface.

    faces : (q,) int64 ids of its faces in the source, increasing
    rows : (p,) int64 the source vertices they use, increasing (patch vertex i is source vertex rows[i])
    surface : _Surface over the patch (vertices numbered 0..p-1, faces in the order of ``faces``)
    vertices : (p, 3) float64, labels : (p,) int64 the source's rows ``rows`` of them
    """

    faces: np.ndarray
    rows: np.ndarray
    surface: _Surface
    vertices: np.ndarray
    labels: np.ndarray


@helper
def _compact(faces, face_ids):
    """The vertices (p,) that faces[face_ids] use, increasing, and those faces (q, 3) over 0..p-1: a
    hash map from vertex to slot (``np.unique`` sorts all 3q corners, several times slower), then the
    p vertices sorted and the slots renumbered by rank."""
    q = face_ids.shape[0]
    size = 16
    while size < 6 * q:
        size *= 2
    keys = np.full(size, -1, np.int64)
    slots = np.empty(size, np.int64)
    found = np.empty(3 * q, np.int64)
    local = np.empty((q, 3), np.int64)
    p = 0
    for i in range(q):
        for c in range(3):
            v = faces[face_ids[i], c]
            h = (v * 0x9E3779B1) & (size - 1)
            while keys[h] != v and keys[h] >= 0:
                h = (h + 1) & (size - 1)
            if keys[h] < 0:
                keys[h] = v
                found[p] = v
                p += 1
            local[i, c] = h                       # the slot, renumbered below
    rows = np.sort(found[:p])
    for rank in range(p):
        h = (rows[rank] * 0x9E3779B1) & (size - 1)
        while keys[h] != rows[rank]:
            h = (h + 1) & (size - 1)
        slots[h] = rank
    for i in range(q):
        for c in range(3):
            local[i, c] = slots[local[i, c]]
    return rows, local


@helper
def _patch_topology(vertices, positions, labels, boundary, rows, faces):
    """The patch's arrays in one pass (a dozen numpy calls cost more than the work on a few hundred
    faces), welded by rest position and label exactly as ``topology.checked_topology`` welds and
    numbers (-0.0 as +0.0): its surface positions (p, 3), the welded vertex of each vertex (p,), its
    ``WeldedMesh`` (as a tuple), the welded vertices (increasing) that carry a ``boundary`` flag, and
    the patch's rows of ``vertices`` (p, 3) and ``labels`` (p,) (read here anyway: a stroke reuses
    them): the fields of ``records.PatchArrays`` from ``positions`` on.

    vertices, positions (n, 3), labels (n,), boundary (n,): the source's ; rows (p,) ; faces (q, 3)
    over 0..p-1
    """
    p, q = rows.shape[0], faces.shape[0]
    source_bits = vertices.view(np.uint64)
    bits = np.empty((p, 4), np.uint64)
    patch_positions, patch_vertices, patch_labels = np.empty((p, 3)), np.empty((p, 3)), np.empty(p, np.int64)
    for i in range(p):
        for k in range(3):
            bits[i, k] = np.uint64(0) if vertices[rows[i], k] == 0.0 else source_bits[rows[i], k]
            patch_positions[i, k] = positions[rows[i], k]
            patch_vertices[i, k] = vertices[rows[i], k]
        patch_labels[i] = labels[rows[i]]
        bits[i, 3] = np.uint64(patch_labels[i])
    welded, representative = _weld_positions(bits)
    w = representative.shape[0]
    welded_faces = np.empty((q, 3), np.int64)
    for f in range(q):
        for k in range(3):
            welded_faces[f, k] = welded[faces[f, k]]
    vertex_edge_ids, vertex_edges = _unique_pairs(*_corner_pairs(faces, np.arange(p)))
    vertex_edge_edge, edges = _unique_pairs(welded[vertex_edges[:, 0].copy()], welded[vertex_edges[:, 1].copy()])
    face_vertex_edges = vertex_edge_ids.reshape(q, 3)
    face_edges = np.empty((q, 3), np.int64)
    for f in range(q):
        for k in range(3):
            face_edges[f, k] = vertex_edge_edge[face_vertex_edges[f, k]]
    ef_offsets, ef_faces, _ = incidence(face_edges, edges.shape[0])
    welded_positions = np.empty((w, 3))
    for v in range(w):
        for k in range(3):
            welded_positions[v, k] = patch_positions[representative[v], k]
    vf_offsets, vf_faces, _ = incidence(welded_faces, w)
    flagged = np.zeros(w, np.bool_)
    for i in range(p):
        flagged[welded[i]] = flagged[welded[i]] or boundary[rows[i]]
    mesh = (welded_positions, welded_faces, face_edges, edges, ef_offsets, ef_faces, vf_offsets, vf_faces)
    return patch_positions, welded, mesh, np.flatnonzero(flagged), patch_vertices, patch_labels


def patch_surface(source, face_ids) -> Patch:
    """The surface of the faces ``face_ids`` (increasing ids into ``source.faces``) of ``source``.

    source : a surgery source (``splice.py``): positions, faces, vertices, labels, boundary, diagonal,
        affines
    """
    arrays, tree = _patch_arrays(source.vertices, source.positions, source.labels, source.boundary, source.faces,
                                 face_ids)
    patch = PatchArrays(*arrays)
    bvh = TriangleBVH.of_tree(tree, patch.positions, patch.faces)
    surface = _Surface(patch.positions, patch.faces, patch.welded, WeldedMesh(*patch.mesh), bvh, patch.boundary,
                       source.diagonal, source.affines)
    return Patch(np.asarray(face_ids, np.int64), patch.rows, surface, patch.vertices, patch.labels)


@kernel()
def _patch_arrays(vertices, positions, labels, boundary, faces, face_ids):
    """The patch of the faces ``face_ids`` (increasing) of a source's arrays (as ``_patch_topology``
    takes them, and its ``faces`` (m, 3)): ``records.PatchArrays`` as a tuple -- its rows (p,) and
    faces (q, 3) over 0..p-1 (``_compact``), then ``_patch_topology``'s arrays (welded by rest position
    and label, as ``surface.tear_topology``: a posed surface's copies of a vertex skin alike, but
    rounding could part them) -- and the fields of its BVH's tree (``bvh._tree``). ``settle._settle``
    runs it every round; ``patch_surface`` from Python."""
    rows, local = _compact(faces, face_ids)
    positions, welded, mesh, flagged, patch_vertices, patch_labels = _patch_topology(
        vertices, positions, labels, boundary, rows, local)
    patch = (face_ids, rows, local, positions, welded, mesh, flagged, patch_vertices, patch_labels)
    return patch, _tree(positions, local, ONE_LEAF)


@helper
def _region(blades, margin, plane, has_plane, snap, diagonal):
    """The query of ``_faces_in_region``: (lo, hi) the box of ``blades`` (4, 3) widened by ``margin``
    and a few snap distances, the plane (4,) (zero: none) and the distance ``delta`` from it."""
    pad = margin + 4.0 * snap
    lo, hi = np.empty(3), np.empty(3)
    scale = diagonal
    for k in range(3):
        lo[k] = min(min(blades[0, k], blades[1, k]), min(blades[2, k], blades[3, k])) - pad
        hi[k] = max(max(blades[0, k], blades[1, k]), max(blades[2, k], blades[3, k])) + pad
        scale = max(scale, diagonal + max(abs(lo[k]), abs(hi[k])))
    if not has_plane:
        return lo, hi, np.zeros(4), np.inf
    # (the rounding of normal·x - offset, which the classification computes otherwise, grows with the
    # coordinates: a model far from the origin; the plane is a dual plane n̂ + d e∞: its signed
    # distance is n̂·x - d)
    return lo, hi, plane.copy(), 2.0 * snap + 16.0 * _EPS * scale


@helper
def _faces_in_region(bvh, blades, margin, plane, has_plane, snap, diagonal):
    """Increasing ids of the faces of ``bvh`` (BVHArrays as a tuple) within 2 ``snap`` distances of
    ``plane`` (any plane when not ``has_plane``) that touch the bounding box of ``blades`` (4, 3)
    (handle, tip, handle, tip) widened by ``margin`` and a few snap distances (the region's test rounds;
    a face that touches the box is kept); ``diagonal`` the surface's bounding-box diagonal."""
    lo, hi, query, delta = _region(blades, margin, plane, has_plane, snap, diagonal)
    return np.sort(_faces_near_plane(bvh, lo, hi, query[:3].copy(), query[3], delta))
