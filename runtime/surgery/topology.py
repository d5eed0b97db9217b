"""The position-welded topology of a triangle mesh, shared by cut and tear.

Real files duplicate vertices along UV and normal seams: two rows of ``rig.vertices`` with the same
position and different NORMAL/TEXCOORD_0 (Fox is fully unindexed: no face shares a vertex with
another). An operation that walks the surface (a cut following crossed edges, a tear crossing from face
to face, boundary loops) must see through those copies, or it stops at the first seam and leaves the
copies of a seam edge cut at different places (a crack). So it works on the *welded* mesh, in which
vertices with bitwise-equal positions are one, while the output keeps the attribute-split vertices.

Vocabulary (used by the field names below)

* vertex: a row of the mesh's vertex array (attribute-split);
* welded vertex: a class of vertices with bitwise-equal positions (``-0.0`` equals ``0.0``); numbered
  by first appearance, so welded vertex ``w`` is represented by its lowest vertex ``representative[w]``;
* corner edge ``k`` of face ``f``: from ``faces[f, k]`` to ``faces[f, (k + 1) % 3]`` (the face's own
  direction, counter-clockwise);
* vertex edge: an undirected pair of vertices joined by some corner edge (a seam edge has two or more,
  one per copy; faces that share both vertices share the vertex edge);
* edge: an undirected pair of welded vertices joined by some corner edge.

``topology(vertices, faces)`` builds it in a few linear passes in numba (a hash table welds positions:
``weld.py``; edges are deduplicated in buckets by their lower end, a counting sort), and
``rig_topology(rig)`` caches
it per rig, which is how cut and tear use it (rigs are immutable by convention: a rig whose arrays are
modified in place after a first call keeps its stale topology; see ``clear_topology_cache``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared import cache
from .._shared.cache import rig_cached
from .._shared.frozen import kernel_array
from .._shared.jit import I1, I2, i8, kernel
from ..errors import InvalidInputError
from .loops import directed_loops
from .weld import _weld

__all__ = ["Topology", "topology", "rig_topology", "clear_topology_cache"]


@kernel((I1, I1), cost=0.7)
def _unique_pairs(a, b):
    """Ids of the unordered pairs {a[i], b[i]} (non-negative int64).

    Buckets by the lower element (a counting sort, cache-friendly where a hash table over millions of
    keys is not), then deduplicates within each bucket: by scanning for the small buckets of a mesh,
    through a table indexed by the higher element for large ones (a fan around a pole). Ids increase
    with the lower element, then with first appearance.

    returns ids (N,) int64, pairs (u, 2) int64 with pairs[j, 0] <= pairs[j, 1]
    """
    n = a.shape[0]
    top = 0
    for i in range(n):
        top = max(top, a[i], b[i])
    offsets = np.zeros(top + 2, np.int64)
    for i in range(n):
        offsets[min(a[i], b[i]) + 1] += 1
    for v in range(top + 1):
        offsets[v + 1] += offsets[v]
    fill = offsets[:-1].copy()
    member = np.empty(n, np.int64)               # pair indices grouped by lower element, in order
    for i in range(n):
        lo = min(a[i], b[i])
        member[fill[lo]] = i
        fill[lo] += 1
    ids = np.empty(n, np.int64)
    pairs = np.empty((n, 2), np.int64)
    id_of_hi = np.full(0, -1, np.int64)          # for large buckets: pair id by higher element
    count = 0
    for lo in range(top + 1):
        s, e = offsets[lo], offsets[lo + 1]
        large = e - s > 32
        if large and id_of_hi.shape[0] == 0:
            id_of_hi = np.full(top + 1, -1, np.int64)
        for q in range(s, e):
            i = member[q]
            hi = max(a[i], b[i])
            found = -1
            if large:
                found = id_of_hi[hi]
            else:
                for r in range(s, q):
                    j = member[r]
                    if max(a[j], b[j]) == hi:
                        found = ids[j]
                        break
            if found < 0:
                pairs[count, 0] = lo
                pairs[count, 1] = hi
                found = count
                count += 1
                if large:
                    id_of_hi[hi] = found
            ids[i] = found
        if large:                                # reset the table for the next large bucket
            for q in range(s, e):
                i = member[q]
                id_of_hi[max(a[i], b[i])] = -1
    return ids, pairs[:count].copy()


@kernel((I2, i8), cost=0.3)
def incidence(table, n):
    """CSR incidence lists item -> (face, corner) of a (m, 3) per-face table of items < n (the
    faces' vertices, or their edges): offsets (n + 1,), faces (3m,) in increasing order within each
    item, corners (3m,) int8."""
    m = table.shape[0]
    offsets = np.zeros(n + 1, np.int64)
    for f in range(m):
        for k in range(3):
            offsets[table[f, k] + 1] += 1
    for e in range(n):
        offsets[e + 1] += offsets[e]
    fill = offsets[:-1].copy()
    faces = np.empty(3 * m, np.int64)
    corners = np.empty(3 * m, np.int8)
    for f in range(m):
        for k in range(3):
            e = table[f, k]
            faces[fill[e]] = f
            corners[fill[e]] = k
            fill[e] += 1
    return offsets, faces, corners


@kernel((I2, I1), cost=0.2)
def _corner_pairs(faces, vertex_map):
    """Endpoints (3m,) of every corner edge after mapping vertices through ``vertex_map``."""
    m = faces.shape[0]
    a = np.empty(3 * m, np.int64)
    b = np.empty(3 * m, np.int64)
    for f in range(m):
        for k in range(3):
            a[3 * f + k] = vertex_map[faces[f, k]]
            b[3 * f + k] = vertex_map[faces[f, (k + 1) % 3]]
    return a, b


@kernel()
def _find_pairs(pairs, a, b):
    """Row of ``pairs`` (u, 2), sorted within rows, holding each {a[i], b[i]}, or -1: one pass of
    ``_unique_pairs`` over the table and the queries together."""
    u = pairs.shape[0]
    ids, unique = _unique_pairs(np.concatenate((pairs[:, 0], a)), np.concatenate((pairs[:, 1], b)))
    row = np.full(unique.shape[0], -1, np.int64)
    for j in range(u):
        row[ids[j]] = j
    out = np.empty(a.shape[0], np.int64)
    for i in range(a.shape[0]):
        out[i] = row[ids[u + i]]
    return out


# ---- the data structure -------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Topology:
    """Welded topology of a triangle mesh (see the module docstring for the vocabulary).

    Parameters
    ----------
    welded : (n,) int64
        The welded vertex of each vertex.
    representative : (w,) int64
        The first vertex of each welded vertex.
    faces : (m, 3) int64
        The faces over welded vertices (same order and corners as the mesh's).
    vertex_edges : (u, 2) int64
        The vertex edges, lower vertex index first, ordered by it.
    face_vertex_edges : (m, 3) int64
        The vertex edge of each corner edge.
    vertex_edge_edge : (u,) int64
        The (welded) edge of each vertex edge.
    edges : (e, 2) int64
        The welded edges, lower welded id first, ordered by it.
    face_edges : (m, 3) int64
        The edge of each corner edge.
    edge_face_offsets : (e + 1,) int64
        CSR offsets: the faces of edge ``i`` are
        ``edge_face_faces[edge_face_offsets[i]:edge_face_offsets[i + 1]]``.
    edge_face_faces : (3m,) int64
        The face of each incidence, increasing within an edge.
    edge_face_corners : (3m,) int8
        The corner k of each incidence: the face runs along the edge from its corner k to corner
        k + 1, which gives the side (see ``edge_directions``).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> topo = cgaskin.rig_topology(arm)
    >>> arm.n_vertices, topo.n_welded, topo.n_edges, topo.faces.shape
    (690, 690, 2064, (1376, 3))
    >>> len(topo.boundary_edges), int(topo.edge_face_counts.max())     # closed: two faces an edge
    (0, 2)
    """

    welded: np.ndarray
    representative: np.ndarray
    faces: np.ndarray
    vertex_edges: np.ndarray
    face_vertex_edges: np.ndarray
    vertex_edge_edge: np.ndarray
    edges: np.ndarray
    face_edges: np.ndarray
    edge_face_offsets: np.ndarray
    edge_face_faces: np.ndarray
    edge_face_corners: np.ndarray

    @property
    def n_welded(self) -> int:
        return len(self.representative)

    @property
    def n_edges(self) -> int:
        return len(self.edges)

    @property
    def edge_face_counts(self) -> np.ndarray:
        """(e,) int64, number of faces on each edge: 1 on a boundary, 2 inside a manifold surface."""
        return np.diff(self.edge_face_offsets)

    @property
    def boundary_edges(self) -> np.ndarray:
        """(b,) int64 ids of the edges with exactly one face."""
        return np.flatnonzero(self.edge_face_counts == 1)

    @property
    def nonmanifold_edges(self) -> np.ndarray:
        """(k,) int64 ids of the edges with more than two faces."""
        return np.flatnonzero(self.edge_face_counts > 2)

    def edge_faces(self, edge: int) -> np.ndarray:
        """The faces on one edge.

        Parameters
        ----------
        edge : int
            An edge id, in [0, e).

        Returns
        -------
        (k,) int64
            The faces with that edge, increasing (a view of ``edge_face_faces``).
        """
        return self.edge_face_faces[self.edge_face_offsets[edge]:self.edge_face_offsets[edge + 1]]

    def edge_directions(self) -> np.ndarray:
        """The direction each face runs along each of its edges.

        Returns
        -------
        (3m,) bool
            Per incidence of ``edge_face_faces``: True when the face runs along its edge from
            ``edges[e, 0]`` to ``edges[e, 1]``. A consistently oriented manifold edge has one of each.
        """
        f, k = self.edge_face_faces, self.edge_face_corners.astype(np.int64)
        return self.faces[f, k] < self.faces[f, (k + 1) % 3]

    def find_edges(self, a, b) -> np.ndarray:
        """The edges joining pairs of welded vertices.

        Parameters
        ----------
        a, b : (k,) int
            The welded vertices of each pair {a[i], b[i]}, in either order.

        Returns
        -------
        (k,) int64
            The edge id of each pair, -1 where no edge joins them.
        """
        a = np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
        b = np.ascontiguousarray(b, dtype=np.int64).reshape(-1)
        if len(a) == 0:
            return np.empty(0, np.int64)
        return _find_pairs(self.edges, a, b)

    def boundary_loops(self) -> list:
        """The closed loops of the mesh's boundary edges (one face).

        Only chains that close are returned (an open chain is impossible on a boundary of a manifold
        surface, but a non-manifold vertex can make one). Where a welded vertex starts two boundary
        edges (two holes touching at a vertex), the loops are split there arbitrarily.

        Returns
        -------
        list of list of int
            Each loop's welded vertex ids, in the direction its faces run along it (counter-clockwise
            around the hole when seen from the side the normals point to); empty for a closed mesh.
        """
        be = self.boundary_edges
        if len(be) == 0:
            return []
        inc = self.edge_face_offsets[be]
        f, k = self.edge_face_faces[inc], self.edge_face_corners[inc].astype(np.int64)
        start, end = self.faces[f, k], self.faces[f, (k + 1) % 3]
        return directed_loops(start, end)


def topology(vertices, faces, labels=None) -> Topology:
    """Build the welded topology of a triangle mesh.

    vertices : (n, 3) float, finite
    faces : (m, 3) int, indices in [0, n)
    labels : optional (n,) int64: vertices weld only when their labels are equal too (the tear's)
    returns Topology (0.5 ms for the 5k-face arm, 0.3-0.6 s for 1.26M faces on a 2-vCPU machine)
    """
    vertices = np.asarray(vertices)
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidInputError(f"vertices must have shape (n, 3), got {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and faces.dtype.kind not in "iu"):
        raise InvalidInputError(f"faces must be an (m, 3) integer array, got {faces.shape} {faces.dtype}")
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise InvalidInputError(f"faces hold indices outside [0, {len(vertices)})")
    if not np.isfinite(vertices).all():
        raise InvalidInputError("vertices hold non-finite values (NaN or inf)")
    if labels is not None:
        labels = np.asarray(labels)
        if labels.shape != (len(vertices),) or (labels.size and labels.dtype.kind not in "iu"):
            raise InvalidInputError(f"labels must be ({len(vertices)},) integers, one per vertex, got "
                                    f"{labels.shape} {labels.dtype}")
    return checked_topology(vertices, faces, labels)


def boundary_flags(vertices, faces, labels=None) -> np.ndarray:
    """(n,) bool: the vertices on a boundary edge (one face) of the welded mesh (checked input, as
    ``checked_topology``): what ``topology(...).boundary_edges`` gives, in a third of its memory."""
    welded, representative = _weld(vertices, labels)
    edge, edges = _unique_pairs(*_corner_pairs(faces, welded))    # the welded edge of each corner edge
    on_boundary = np.zeros(len(representative), bool)
    on_boundary[edges[np.bincount(edge, minlength=len(edges)) == 1].reshape(-1)] = True
    return on_boundary[welded]


def checked_topology(vertices, faces, labels=None) -> Topology:
    """``topology`` of input already checked (finite (n, 3) float vertices, (m, 3) int64 faces that
    index them): a tear stroke builds one per patch, where the checks would cost more than the build."""
    welded, representative = _weld(vertices, labels)
    welded_faces = welded[faces]
    m = len(faces)
    vertex_edge_ids, vertex_edges = _unique_pairs(*_corner_pairs(faces, np.arange(len(vertices))))
    # the welded edge of each vertex edge: its pair of welded ids, deduplicated the same way
    vertex_edge_edge, edges = _unique_pairs(welded[vertex_edges[:, 0]], welded[vertex_edges[:, 1]])
    face_vertex_edges = vertex_edge_ids.reshape(m, 3)
    face_edges = vertex_edge_edge[face_vertex_edges]
    offsets, inc_faces, inc_corners = incidence(face_edges, len(edges))
    return Topology(welded=welded, representative=representative, faces=welded_faces,
                    vertex_edges=vertex_edges, face_vertex_edges=face_vertex_edges,
                    vertex_edge_edge=vertex_edge_edge, edges=edges, face_edges=face_edges,
                    edge_face_offsets=offsets, edge_face_faces=inc_faces, edge_face_corners=inc_corners)


def _build_topology(rig) -> Topology:
    # (the writeable buffers behind the rig's read-only arrays: the kernels' one compiled type)
    return topology(kernel_array(rig.vertices), kernel_array(rig.faces))


def rig_topology(rig) -> Topology:
    """The welded topology of a rig's mesh, built on first use and cached while the rig lives.

    Parameters
    ----------
    rig : Rig
        The model (immutable by convention: see ``clear_topology_cache``).

    Returns
    -------
    Topology
        ``topology(rig.vertices, rig.faces)``, the same object on every call for the same rig
        (``cgaskin._shared.cache.rig_cached``).

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> topo = cgaskin.rig_topology(arm)
    >>> topo is cgaskin.rig_topology(arm), topo.n_edges
    (True, 2064)
    >>> topo.find_edges([0, 0], [1, 600])                   # the edge joining each pair, -1: none
    array([ 1, -1])
    """
    return rig_cached(rig, "topology", _build_topology)


def clear_topology_cache() -> None:
    """Forget every cached topology (and everything else cached per rig: ``cgaskin._shared.cache``)."""
    cache.clear()
