"""A stroke's patch and its located ends, settled (compiled; ``splice._stroke`` runs it).

``guess.py`` guesses the tear plane and margin on the whole surface; the patch of that plane and margin
(``patch.py``: the faces near the plane inside the region's box, compacted, welded, with a BVH of one
leaf) then has its ends located on it (``locate.py``), and the patch is taken again with the plane and
margin ``locate`` found until the two agree (once, unless the guess was off). The steps hand each other
a few dozen arrays: run from Python, every returned array cost a boxing and every step a call, a third of
a small mesh's stroke; compiled, they stay where they are.
"""
from __future__ import annotations

from ..._shared.jit import B1, F1, F2, I1, I2, b1, callee, f8, i8, record
from ..bvh import BVH_ARRAYS
from ..surface import WELDED_MESH
from .locate import _ends
from ..posed_bounds import POSING, _pose_region
from .patch import _faces_in_region, _patch_arrays, _region
from .records import OK
from .region import _margin

#: the numba types of a ``records.StrokeSource`` and a ``records.PatchArrays`` (as tuples)
STROKE_SOURCE = record(BVH_ARRAYS, B1, F2, F2, I1, I2, I2, F2, F2, b1, i8, f8)
PATCH_ARRAYS = record(I1, I1, I2, F2, I1, WELDED_MESH, I1, F2, I1)

#: how often the patch is taken again before giving up (the plane of a patch is its own: twice is enough)
ROUNDS = 4


@callee((STROKE_SOURCE, F2, F1, b1, f8, f8, f8, POSING), cost=16.0)
def _settle(source, blades, plane, has_plane, margin, snap, min_sine, posing):
    """The stroke's patch and its located ends, settled, for ``blades`` (4, 3) handle and tip at t_i,
    then at t_(i+1), on ``source`` (``records.StrokeSource``: its BVH, boundary flags, vertices,
    positions, labels, faces and diagonal); the guessed ``plane`` (4,) (``has_plane`` False: none; the
    patch then takes every face in the box, and the plane ``locate`` chooses selects it again) and
    ``margin``; ``snap`` the absolute snap distance; ``posing`` (``posed_bounds.Posing``) poses the
    region of each round first when active.

    returns settled (False: the ends' status is not OK, or the rounds ran out), the patch
    (``records.PatchArrays`` as a tuple), the fields of its BVH's tree (``BVHArrays``' first seven),
    and the fields of ``Ends``
    """
    bvh, boundary, vertices, positions, labels, faces, _, _, _, _, _, diagonal = source
    a0, b0, a1, b1 = blades[0], blades[1], blades[2], blades[3]
    for round_ in range(ROUNDS):
        lo, hi, query, delta = _region(blades, margin, plane, has_plane, snap, diagonal)
        _pose_region(bvh, posing, query, lo, hi, delta)        # what the region query below reaches
        face_ids = _faces_in_region(bvh, blades, margin, plane, has_plane, snap, diagonal)
        patch, tree = _patch_arrays(vertices, positions, labels, boundary, faces, face_ids)
        _, _, local, patch_positions, _, mesh, patch_boundary, _, _ = patch
        ends = _ends(tree + (patch_positions, local), a0, b0, a1, b1, patch_positions, local, mesh, patch_boundary,
                     snap, min_sine)
        status, _, points, _, hit_faces, located, _ = ends         # (the fields of ``Ends``)
        settled = status == OK
        if settled:
            welded_positions, welded_faces = mesh[0], mesh[1]          # (``WeldedMesh``'s first fields)
            needed = _margin(welded_positions, welded_faces, hit_faces, points[0], points[1])
            same = has_plane
            for k in range(4):
                same = same and located[k] == plane[k]
            settled = same and needed <= margin
            plane, has_plane, margin = located.copy(), True, max(margin, needed)
        if settled or status != OK or round_ == ROUNDS - 1:
            return settled, patch, tree, ends
    raise AssertionError("unreachable")
