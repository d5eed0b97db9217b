"""The faces around a drill's rim, refined until the rim can be drawn finely: longest-edge bisection.

A hole is round only if the mesh has vertices close together where the bit's surface crosses it; a real
model's faces are often larger than the hole. So before the rim is placed, every face that the bit's
surface passes through (part of it inside the bit, part outside: ``bit.surface_crosses``) and whose longest
edge is longer than ``step`` is bisected on its longest edge, and a face that shares a bisected edge is
bisected too (on its longest edge first, then on the shared one: Rivara's longest-edge bisection, which
keeps the angles of the refined faces bounded and leaves no vertex in the middle of a neighbour's edge).
Rounds repeat until no face the surface passes through is longer than ``step``: the rim's edges are then
at most ``step`` long, and a face left outside the bit reaches into it by no more than such an edge's sagitta.

The faces are the patch's (``patch.py``); edges are marked by their welded points, so that the
bisection of a seam edge is seen from both sides. The rounds run in one compiled call
(``rounds.refine_rounds``), which also takes in the input faces beyond the patch that a closure reaches.
"""
from __future__ import annotations

from ...errors import InternalError
from .bisection import split_marked
from .patch import Patch
from .rounds import REFINED, InputMesh, Refined, refine_rounds

#: refinement rounds before giving up (each halves the faces near the rim: 2^60 is beyond any model)
MAX_ROUNDS = 60


def refine(patch: Patch, first, bit, step: float) -> None:
    """Fill a new (empty) patch with the input faces ``first`` (k,) and bisect its faces that the bit's
    surface passes through until none is longer than ``step`` (module docstring), taking in the input
    faces beyond the patch that share a bisected edge."""
    start, end, radius = bit
    topology = patch.topology
    mesh = InputMesh(patch.positions, patch.mesh_faces, topology.welded, topology.faces, topology.face_edges,
                     topology.edge_face_offsets, topology.edge_face_faces)
    made = Refined(*refine_rounds(first, tuple(mesh), (patch.row_of, patch.point_of, patch.is_taken), start, end,
                                  radius, step, MAX_ROUNDS))
    patch.grow(made)
    if made.status != REFINED:
        raise InternalError(f"the faces near the bit did not become shorter than {step:g} in {MAX_ROUNDS} rounds")


def bisect_marked(patch: Patch, marked, place=None) -> None:
    """Split every face with marked edges (codes of point pairs): on its longest edge if it is marked
    (else the first marked), then each half on the marked edge it keeps (``bisection.split_marked``).
    Each marked edge gets one new point, at its midpoint or, when given, where ``place(a (k,), b (k,))
    -> (k, 3)`` says for the edges between points a and b (called just before the k points are added);
    each vertex edge on it gets one new row (a seam's copies share the point). The faces split go, their
    halves come after the others."""
    faces, made_from, row_parents, row_points, point_parents = split_marked(
        patch.faces, patch.row_point, patch.point_array(), marked, patch.n_rows, patch.n_points)
    a, b = point_parents[:, 0], point_parents[:, 1]
    points = patch.point_array()
    patch.add_points(0.5 * (points[a] + points[b]) if place is None else place(a, b))
    patch.new_rows(row_points, row_parents[:, 0], row_parents[:, 1], 0.5)
    patch.replace_faces(faces, patch.face_source[made_from])
