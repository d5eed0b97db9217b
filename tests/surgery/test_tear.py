"""The scalpel tear (cgaskin.tear, cgaskin.tear_stroke), fixed cases: which hit starts the path, strokes
that miss or are malformed, paths along edges, inside one face, through a corner, across seams, into
an open border; labels, a caller's BVH, faces of zero area.
"""
from __future__ import annotations

import numpy as np
import pytest

from cgaskin import TriangleBVH, capsule_arm, tear, tear_stroke
from cgaskin.errors import InvalidInputError, MissesMeshError
from cgaskin.surgery.tear import TEAR_LABEL, tear_topology

from tests.helpers.tear_checks import (areas, capsule_blades, check_stroke, diagonal, face_normal, get_rig,
                                       save_gltf)


# ---- fixed cases ---------------------------------------------------------------------------------------
def test_first_hit_from_the_handle():
    rig = get_rig("capsule")
    result = tear_stroke(rig, *capsule_blades(1.02, 1.45))
    # the blade crosses the capsule twice; S is the crossing nearer the handle (top, y > 0)
    assert result.hits[0, 1] > 0 and result.hits[1, 1] > 0
    flipped = tear_stroke(rig, *(b[::-1] for b in capsule_blades(1.02, 1.45)))
    assert flipped.hits[0, 1] < 0 and flipped.hits[1, 1] < 0


def test_scalpel_that_misses_says_which():
    rig = get_rig("capsule")
    hit_from, hit_to = capsule_blades(1.0, 1.5)
    away = np.array([[1.0, 5.0, 5.0], [1.0, 4.0, 5.0]])
    with pytest.raises(MissesMeshError, match="scalpel_from"):
        tear(rig, away, hit_to)
    with pytest.raises(MissesMeshError, match="scalpel_to"):
        tear(rig, hit_from, away)
    short = np.array([[1.0, 1.0, 0.0], [1.0, 0.5, 0.0]])    # stops short of the skin
    with pytest.raises(MissesMeshError):
        tear(rig, short, hit_to)


@pytest.mark.parametrize("bad", [
    dict(scalpel_from=[[0, np.nan, 0], [0, 0, 0]]),
    dict(scalpel_from=[[1.0, 1.0, 0.0]]),
    dict(scalpel_from=[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0]]),              # zero-length blade
    dict(scalpel_to=np.zeros((2, 4))),
    dict(scalpel_to="blade"),
    dict(opening=-0.1),
    dict(opening=np.inf),
    dict(opening="wide"),
    dict(pose="rest"),
])
def test_bad_input(bad):
    rig = get_rig("capsule")
    hit_from, hit_to = capsule_blades(1.0, 1.5)
    args = dict(scalpel_from=hit_from, scalpel_to=hit_to)
    args.update(bad)
    with pytest.raises(InvalidInputError):
        tear(rig, **args)


def test_not_a_rig_and_foreign_pose():
    rig = get_rig("capsule")
    with pytest.raises(InvalidInputError):
        tear("rig", *capsule_blades(1.0, 1.5))
    other = capsule_arm(n_joints=2)
    with pytest.raises(InvalidInputError, match="skeleton"):
        tear(rig, *capsule_blades(1.0, 1.5), pose=other.rest_pose())


def test_stroke_that_does_not_move_is_refused():
    rig = get_rig("capsule")
    blade = capsule_blades(1.0, 1.0)[0]
    with pytest.raises(InvalidInputError, match="does not move"):
        tear(rig, blade, blade)


def test_blade_sliding_along_itself_falls_back():
    """S_i on the line of the blade at t_{i+1}: the plane falls back to the blade at t_i."""
    rig = get_rig("capsule")
    s = tear_stroke(rig, *capsule_blades(1.0, 1.4)).hits
    a1 = s[1] + (s[1] - s[0])                      # the blade at t_{i+1} lies on the line S_i S_{i+1}
    b1 = s[1] - 0.5 * (s[1] - s[0])
    result = tear_stroke(rig, capsule_blades(1.0, 1.4)[0], np.array([a1, b1]))
    assert np.isfinite(result.plane).all()
    check_stroke(rig, result, None)


def test_path_along_edges_in_the_plane():
    """A plane that holds a row of mesh edges (the capsule's top line z = 0): the path goes through
    the vertices and along the edges, and still opens."""
    rig = get_rig("capsule")
    result = tear_stroke(rig, *capsule_blades(1.0, 1.5, 0.0, 0.0))
    assert (result.kinds == 0).all()               # every path point is an existing vertex
    check_stroke(rig, result, None)
    assert result.split[1:-1].all()


def test_stroke_inside_one_face_still_opens():
    rig = get_rig("capsule")
    faces, points = np.asarray(rig.faces), rig.vertices
    f = 500
    a, b, c = points[faces[f]]
    p0, p1 = 0.6 * a + 0.2 * b + 0.2 * c, 0.2 * a + 0.6 * b + 0.2 * c
    n = face_normal(points, faces[f])
    result = tear_stroke(rig, np.array([p0 + 0.1 * n, p0 - 0.1 * n]), np.array([p1 + 0.1 * n, p1 - 0.1 * n]))
    assert len(result.points) == 3 and result.split.tolist() == [False, True, False]
    check_stroke(rig, result, None)


def test_stroke_towards_a_corner_on_the_plane_leaves_no_sliver():
    """A stroke inside one face whose line runs through a corner of that face (here the capsule's
    pole, which the tear plane holds): the end node lies on the fan edge from the midpoint to that
    corner, which is split there instead of leaving a triangle of zero area; the next stroke from the
    same blade then starts at the end vertex and continues the slit (a case hypothesis found)."""
    rig = get_rig("capsule")
    blade_0 = np.array([[-0.3424427784925041, -0.10355683722229911, 0.02059873565023741],
                        [-0.1237259026236233, -0.06005134565733722, 0.01194495532903511]])
    blade_1 = np.array([[-0.3443222962082748, -0.09446749372898598, 0.0187907528180556],
                        [-0.12560542033939398, -0.05096200216402409, 0.0101369724968533]])
    blade_2 = np.array([[-0.30730265569658965, 0.01497309382001193, 0.07527482588065143],
                        [-0.1673238551405059, 0.00943467441444245, 0.04743131127907582]])
    first = tear_stroke(rig, blade_0, blade_1)
    assert list(first.kinds) == [2, 2, 2]                     # inside one face
    torn = first.rig
    points, faces = np.asarray(torn.vertices), np.asarray(torn.faces)
    assert areas(points, faces).min() > 1e-9 * diagonal(points) ** 2
    second = tear_stroke(torn, blade_1, blade_2)
    assert second.kinds[0] == 0 and second.split[0]
    np.testing.assert_array_equal(second.points[0], first.points[-1])
    check_stroke(torn, second, None, 0.0)


def test_long_stroke_round_the_capsule_takes_the_short_way():
    rig = get_rig("capsule")
    result = tear_stroke(rig, *capsule_blades(0.2, 2.8))
    assert result.points[:, 1].min() > 0            # along the top, not round the far side
    check_stroke(rig, result, None)


def test_fox_tear_crosses_seams(models_dir):
    """Fox is fully unindexed (no face shares a vertex): only the welded walk gets past a face."""
    rig = get_rig("Fox.glb", models_dir)
    points = rig.vertices
    faces = np.asarray(rig.faces)
    f0 = int(np.argmax(points[faces].mean(axis=1)[:, 1]))     # a face high on the back
    centroid = points[faces[f0]].mean(axis=0)
    diag = diagonal(points)
    dist = np.linalg.norm(points[faces].mean(axis=1) - centroid, axis=1)
    f1 = int(np.flatnonzero((dist > 0.04 * diag) & (dist < 0.08 * diag))[0])
    blades = []
    for f in (f0, f1):
        p, n = points[faces[f]].mean(axis=0), face_normal(points, faces[f])
        blades.append(np.array([p + 0.02 * diag * n, p - 0.02 * diag * n]))
    result = tear_stroke(rig, *blades)
    assert len(result.points) > 3
    check_stroke(rig, result, None)
    # each seam crossing got one new vertex per copy of the edge, each with its own UVs
    assert result.rig.n_vertices > rig.n_vertices + 2 * (len(result.points) - 2)


def test_tear_into_the_border_of_an_open_mesh(models_dir):
    """An end on the border of an open mesh (PlaneWith3Bones, a flat grid) is split too: the slit
    joins the border, whose loop grows by the path (both sides) and the split border edge."""
    rig = get_rig("PlaneWith3Bones.glb", models_dir)               # the square [0, 4]^2 at z = 0

    def blade(x, y):
        return np.array([[x, y, 1.0], [x, y, -1.0]])
    result = tear_stroke(rig, blade(2.13, 2.07), blade(4.0, 2.38))
    assert result.kinds[-1] == 1 and result.split[1:].all() and not result.split[0]
    before, after = tear_topology(rig), tear_topology(result.rig)
    assert len(before.boundary_loops()) == len(after.boundary_loops()) == 1
    k = len(result.points)
    assert len(after.boundary_edges) == len(before.boundary_edges) + 1 + 2 * (k - 1)
    assert len(after.nonmanifold_edges) == 0
    np.testing.assert_array_equal(result.rig.vertices[:rig.n_vertices], rig.vertices)


def test_tear_label_keeps_slits_open_and_exports(tmp_path):
    rig = get_rig("capsule")
    torn = tear(rig, *capsule_blades(1.0, 1.5))
    labels = torn.attributes[TEAR_LABEL][:, 0]
    assert set(np.unique(labels)) == {0.0, 1.0}
    if save_gltf is not None:
        save_gltf(torn, tmp_path / "torn.glb")


def test_user_bvh_is_used_and_checked():
    rig = get_rig("capsule")
    bvh = TriangleBVH(rig.vertices, rig.faces)
    a = tear(rig, *capsule_blades(1.0, 1.5), bvh=bvh)
    b = tear(rig, *capsule_blades(1.0, 1.5))
    np.testing.assert_array_equal(a.faces, b.faces)
    stale = TriangleBVH(rig.vertices + [0.0, 0.01, 0.0], rig.faces)
    with pytest.raises(InvalidInputError, match="bvh"):
        tear(rig, *capsule_blades(1.0, 1.5), bvh=stale)
    # as many faces, over more vertices: refused before any kernel reads a vertex the rig lacks
    padded = np.concatenate((rig.vertices, rig.vertices[:7] + 5.0))
    with pytest.raises(InvalidInputError, match="vertices"):
        tear(rig, *capsule_blades(1.0, 1.5), bvh=TriangleBVH(padded, rig.faces))


def test_points_in_a_face_of_zero_area_get_finite_coordinates():
    """A face of zero area has no barycentric coordinates (the generated kernel divides by its
    area): a path point in one takes its place on the face's longest side."""
    import importlib
    from numba import njit
    coordinates = importlib.import_module("cgaskin.surgery.tear.retriangulate")._segment_coordinates

    @njit
    def call(a, b, c, p):
        return coordinates(a, b, c, p)

    a, b, c = np.array([0.0, 0, 0]), np.array([2.0, 0, 0]), np.array([1.0, 0, 0])
    np.testing.assert_allclose(call(a, b, c, np.array([0.5, 1.0, 0])), (0.75, 0.25, 0.0))
    np.testing.assert_allclose(call(b, c, a, np.array([1.5, 0, 0])), (0.75, 0.0, 0.25))
    np.testing.assert_allclose(call(a, a, a, np.array([0.5, 1.0, 0])), (1.0, 0.0, 0.0))
