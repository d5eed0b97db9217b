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

#: how a stroke's locating steps ended (``guess._guess``, ``locate._ends``): found, a scalpel position
#: that missed the surface, the two points the same, no plane through the points and the blade
OK, FROM_MISSES, TO_MISSES, NO_MOTION, NO_PLANE = 0, 1, 2, 3, 4

# ---- the columns of the records' arrays ----------------------------------------------------------------
#: a path node row (``Path.nodes``): the node (kind, id), and what the segment from the previous node
#: runs through (carrier kind, carrier id); the walk's node table adds the node's parent in its tree
KIND, ID, CARRIER_KIND, CARRIER, PARENT = 0, 1, 2, 3, 4
#: a path point row (``Path.points``): the edge parameter t (of an EDGE node), then x, y, z from
#: ``POINT``; the walk's node table adds the length of the way from the start
EDGE_T, POINT, LENGTH = 0, 1, 4
#: a twin row (``Slit.twins``): the vertex it copies, the far side's rank, the path node
TWIN_OF, TWIN_RANK, TWIN_NODE = 0, 1, 2
#: a moved row (``Slit.moved``): the existing vertex, its side (+1 near, -1 far), the far side's rank
#: (-1 on the near side), the path node
MOVED_VERTEX, MOVED_SIDE, MOVED_RANK, MOVED_NODE = 0, 1, 2, 3


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

    nodes : (k, 4) int64 rows (``KIND``, ``ID``, ``CARRIER_KIND``, ``CARRIER``): the carrier is what
        the segment from the previous node runs through (a face, an edge lying in the plane, or --
        JUMP_CARRIER, id -1 -- an opening of the surface between two boundary points)
    points : (k, 4) float64 rows (``EDGE_T``: the parameter from edges[id, 0], then x, y, z from ``POINT``)
    """

    nodes: np.ndarray
    points: np.ndarray


class StrokeSource(NamedTuple):
    """A source's arrays and values as the compiled stroke takes them (``splice.stroke_splice``).

    bvh : ``BVHArrays`` as a tuple ; boundary (n,) bool ; vertices, positions (n, 3) float64 ;
    labels (n,) int64 ; faces (m, 3) int64 ; joints (n, 4) int64 ; weights (n, 4) float64 ;
    affines (B, 12) float64 (zeros, unused, when not posed) ; posed bool ; top_label int ;
    diagonal float
    """

    bvh: tuple
    boundary: np.ndarray
    vertices: np.ndarray
    positions: np.ndarray
    labels: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    affines: np.ndarray
    posed: bool
    top_label: int
    diagonal: float


class Tolerances(NamedTuple):
    """A stroke's tolerances relative to the diagonal (``tolerances.tol``): snap, min_sine, on_edge."""

    snap: float
    min_sine: float
    on_edge: float


class PatchArrays(NamedTuple):
    """A stroke's patch, settled (``settle._settle``): the faces near the tear plane, renumbered.

    face_ids (q,), rows (p,) int64 its faces and vertices in the source ; faces (q, 3) int64 over
    0..p-1 ; positions (p, 3) float64 ; welded (p,) int64 the welded vertex of each vertex ; mesh :
    its ``WeldedMesh`` as a tuple ; boundary : flags of the welded vertices ; vertices (p, 3) rest
    rows ; labels (p,) int64
    """

    face_ids: np.ndarray
    rows: np.ndarray
    faces: np.ndarray
    positions: np.ndarray
    welded: np.ndarray
    mesh: tuple
    boundary: np.ndarray
    vertices: np.ndarray
    labels: np.ndarray


class WalkEnd(NamedTuple):
    """A walk's start or target node: its kind, id and point (3,)."""

    kind: int
    ident: int
    point: np.ndarray


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

    split : (k,) bool ; twins : (t, 3) int64 rows (``TWIN_OF``, ``TWIN_RANK``, ``TWIN_NODE``), twin i
    being vertex n + v + i ; moved : (s, 4) int64 rows (``MOVED_VERTEX``, ``MOVED_SIDE``,
    ``MOVED_RANK``, ``MOVED_NODE``): the existing vertices that belong to a side ; side_a, side_b :
    (k,) int64 one vertex per node on each side
    """

    split: np.ndarray
    twins: np.ndarray
    moved: np.ndarray
    side_a: np.ndarray
    side_b: np.ndarray


# ---- the walk's own records (step 4; compiled code makes and reads them) ------------------------------
class NodeTable(NamedTuple):
    """The walk's search tree, a row per node, with room for the nodes the walk may push next
    (``walk._room`` grows it).

    ints : (cap, PARENT + 1) int64 a path node row and the node's parent ; floats : (cap, LENGTH + 1)
    float64 a path point row and the length of the way from the start ; target : (cap,) bool whether
    the node is the target
    """

    ints: np.ndarray
    floats: np.ndarray
    target: np.ndarray


class Target(NamedTuple):
    """The node a walk goes to: kind, ident, its edge parameter ``t`` (0 unless an EDGE) and its point
    (x, y, z). (Scalars: a record of arrays handed to a compiled call costs their reference counts.)"""

    kind: int
    ident: int
    t: float
    x: float
    y: float
    z: float


class Reach(NamedTuple):
    """Where a walk's fronts may go: ``vertex_used`` (w,) float64 the shortest length a node of each
    welded vertex was pushed with (inf if none: a front reaching it again by a way as long or longer
    dies), and the swept ``region`` (the blade at both times) widened by ``margin`` (``region.py``)."""

    vertex_used: np.ndarray
    region: tuple
    margin: float
