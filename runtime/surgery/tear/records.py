"""The tear's path node codes and the records handed from step to step (the compiled steps hand each
other their fields as plain tuples, in these orders).

The compiled helpers take these codes (and every other small integer) as np.int64, never as Python
int literals: numba compiles a separate copy of a helper for each literal value it is called with
(also for a loop counter that starts at a literal: ``n = 0`` gives one copy for Literal[int](0) and
one for int64, so such counters start at ``np.int64(0)``).
Helpers that only other kernels call are compiled with no_cpython_wrapper=True: numba then builds
no Python entry point for them, which shortens a cold start by about a tenth (cgaskin.precompile).
"""
from typing import NamedTuple

import numpy as np

# path node kinds
VERTEX, EDGE, FACE = np.int64(0), np.int64(1), np.int64(2)
# how a path segment runs from the previous node: across a face, along an edge in the plane, or
# through an opening of the surface (a jump across an existing slit or hole, between boundary points)
NO_CARRIER, FACE_CARRIER, EDGE_CARRIER, JUMP_CARRIER = np.int64(-1), np.int64(0), np.int64(1), np.int64(2)


# ---- the data handed from step to step -------------------------------------------------------------
class Ends(NamedTuple):
    """Steps 2-3 (``locate``): where the blade meets the skin, the tear plane, the vertices' sides.

    status : int, OK or why not (locate's status codes)
    nodes : (2, 2) int64 (kind, id) of S_i and S_{i+1} ; points : (2, 3) float64 their positions
    hits : (2, 3) float64 the raw scalpel hits ; hit_faces : (2,) int64 the faces hit
    plane : (4,) float64 the tear plane n + d e∞ ; sides : (w,) int8 side of every welded vertex
    """

    status: int
    nodes: np.ndarray
    points: np.ndarray
    hits: np.ndarray
    hit_faces: np.ndarray
    plane: np.ndarray
    sides: np.ndarray


class Path(NamedTuple):
    """Step 4 (``walk``): the path from S_i to S_{i+1}, one row per node.

    nodes : (k, 4) int64 (kind, id, carrier kind, carrier id): the carrier is what the segment from
        the previous node runs through (a face, an edge lying in the plane, or -- JUMP_CARRIER, id -1 --
        an opening of the surface between two boundary points)
    points : (k, 4) float64 (edge parameter t from edges[id, 0], x, y, z)
    """

    nodes: np.ndarray
    points: np.ndarray


class Pieces(NamedTuple):
    """Step 5 (``retriangulate``): the crossed faces split along the path, and the new vertices.

    affected : (a,) int64 faces replaced by their pieces
    tris : (q, 3) int64 the pieces, as vertex ids of the torn mesh (new vertices from n_vertices)
    new_node : (v,) int64 path node of each new vertex
    new_src : (v, 3) int64, new_coef : (v, 3) float64 what each new vertex interpolates
        (``new_vertices.NewVertices``)
    parent : (q,) int64 index in ``affected`` of the face each piece lies in
    """

    affected: np.ndarray
    tris: np.ndarray
    new_node: np.ndarray
    new_src: np.ndarray
    new_coef: np.ndarray
    parent: np.ndarray


class TornFaces(NamedTuple):
    """Step 6a (``slit.torn_faces``): the face list of the torn mesh.

    faces : (m', 3) int64 the kept faces in order, then the pieces ; welded : (m', 3) int64 their
    welded corners (new vertex i is welded n_welded + its path node) ; node_welded : (k,) int64 the
    welded vertex of each path node ; new_positions : (v, 3) float64 ; candidates : (c,) int64 sorted
    rows of ``faces`` that may touch a path node
    """

    faces: np.ndarray
    welded: np.ndarray
    node_welded: np.ndarray
    new_positions: np.ndarray
    candidates: np.ndarray


class Slit(NamedTuple):
    """Step 6b (``slit.open_slit``): which path nodes split, and the far side's vertices.

    split : (k,) bool ; twins : (t, 3) int64 (vertex it copies, far side rank, path node), twin i
    being vertex n + v + i ; moved : (s, 4) int64 (existing vertex that belongs to a side, +1 near /
    -1 far, far side rank or -1, path node) ; side_a, side_b : (k,) int64 one vertex per node on each
    side
    """

    split: np.ndarray
    twins: np.ndarray
    moved: np.ndarray
    side_a: np.ndarray
    side_b: np.ndarray

