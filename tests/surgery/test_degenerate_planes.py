"""Planes through vertices, along edges and containing faces (issue 13): the degenerate cases that axis-
aligned strokes and cuts produce on meshes with axis-aligned rows of vertices, one regression test per
family, for the tear and for the cut.

Families: a vertex on the plane; an edge in the plane; a face in the plane; (tear) the slit's own end on
the plane. Meshes: the procedural capsule arm (rings every 1/12 along x, 16 vertices round, so rows at
z = 0 and y = 0 with their edges lie in axis planes) and staircases of unit voxels
(``tests.helpers.grid_meshes``: treads and risers in grid planes).

Oracles: the tear's invariants (``tests.helpers.tear_checks.check_stroke``), the swept region
(``tests.helpers.swept_region``, independent numpy), the cut's invariants (``tests.helpers.cut_checks.
check_cut``: areas of the halves sum to the original, new vertices on the plane and on their edges,
closed boundaries / watertight caps), and no zero-area face (``grid_meshes.slivers``).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings, strategies as st

from cgaskin import TearPathError, TriangleBVH, capsule_arm, cut_details, tear_stroke
from cgaskin.surgery.tear import tear_topology

from tests.helpers.cut_checks import check_cut
from tests.helpers.grid_meshes import slivers, staircase
from tests.helpers.swept_region import hull_distance
from tests.helpers.tear_checks import check_stroke, pieces

VERTEX, EDGE, FACE = 0, 1, 2
RING = 1.0 / 12.0                       # the capsule's ring spacing along x
TOP_ROW = 0.25                          # the capsule's radius: its top row is y = 0.25, z = 0


# ---- helpers -------------------------------------------------------------------------------------------
def check_in_region(rig, result, blade_from, blade_to):
    """Every path point within the margin of the blades' hull: |S_{i+1} - S_i| plus the longest edge of
    the faces the blades hit (region.py's margin, bounded by the longest edge of the mesh when a blade
    met the surface at a boundary vertex before any face)."""
    bvh = TriangleBVH(rig.vertices, rig.faces)
    corners = np.asarray(rig.vertices)[np.asarray(rig.faces)]
    lengths = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    hit = [bvh.first_hit(*np.asarray(blade, float))[0] for blade in (blade_from, blade_to)]
    longest = lengths.max() if min(hit) < 0 else lengths[hit].max()
    margin = np.linalg.norm(result.points[-1] - result.points[0]) + longest
    blades = np.array([blade_from, blade_to], np.float64)
    assert max(hull_distance(p, blades) for p in result.points) <= margin * (1 + 1e-9)


def check_tear(rig, result, blade_from, blade_to, opening):
    check_stroke(rig, result, None, opening)
    check_in_region(rig, result, blade_from, blade_to)
    assert slivers(result.rig) == 0


def turned_over(rig, result, blade_from, blade_to) -> int:
    """Faces that the opening turned over: the same stroke with opening 0 makes the same faces, and
    each of ``result``'s must keep the side it faces (area vectors with a positive dot product)."""
    closed = tear_stroke(rig, blade_from, blade_to).rig
    assert np.array_equal(closed.faces, result.rig.faces)
    areas = [np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]) for c in
             (np.asarray(r.vertices)[np.asarray(r.faces)] for r in (closed, result.rig))]
    return int(np.count_nonzero(np.sum(areas[0] * areas[1], axis=1) <= 0))


def row_blade(x, row="top"):
    """A blade over the capsule at x, aimed at the axis through the top row (from +y) or the side row
    (from +z)."""
    return ([x, 0.35, 0.0], [x, 0.0, 0.0]) if row == "top" else ([x, 0.0, 0.35], [x, 0.0, 0.0])


def incision(rig, xs, opening, row="top"):
    """Strokes from x[0] to x[1], x[1] to x[2], ... along a row of the capsule, each continuing the
    last; every stroke checked. Returns the torn rig and the results."""
    results = []
    for i, (x0, x1) in enumerate(zip(xs[:-1], xs[1:])):
        blade_from, blade_to = row_blade(x0, row), row_blade(x1, row)
        result = tear_stroke(rig, blade_from, blade_to, opening=opening)
        check_tear(rig, result, blade_from, blade_to, opening)
        # along the row, never beyond the stroke's ends (no detour to the next vertex of the row)
        xmin, xmax = min(x0, x1), max(x0, x1)
        assert (result.points[:, 0] >= xmin - 1e-12).all() and (result.points[:, 0] <= xmax + 1e-12).all()
        assert not result.jumps.any()
        if i > 0:
            # the previous stroke's end, a vertex now: the slit goes on from it (it opens)
            assert result.kinds[0] == VERTEX and result.split[0]
        results.append(result)
        rig = result.rig
    return rig, results


def rotation(seed) -> np.ndarray:
    """A random rotation matrix (3, 3)."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def moved(rig, rotation, shift):
    """``rig`` with its vertices rotated and shifted: the grid planes are no longer axis planes, and
    its vertices lie on them only up to rounding (the tolerances decide)."""
    return rig.with_mesh(np.asarray(rig.vertices) @ rotation.T + shift, rig.faces, rig.joints, rig.weights,
                         dict(rig.attributes))


def cut_checked(rig, normal, point, cap, closed=True):
    with warnings.catch_warnings():
        warnings.simplefilter("error")           # a plane that misses would warn
        result = cut_details(rig, normal, point, cap=cap)
    check_cut(rig, result, closed=closed, capped=cap)
    assert slivers(result.positive) == slivers(result.negative) == 0
    return result


# ---- tear: a vertex on the plane ---------------------------------------------------------------------
@pytest.mark.parametrize("opening", [0.0, 0.002])
def test_tear_through_a_vertex_of_the_row(opening):
    """A stroke at an angle to the row whose plane passes through one vertex (and along none of its
    edges): the path goes through that vertex (no node beside it, no sliver)."""
    rig = capsule_arm()
    vertex = np.array([0.5, TOP_ROW, 0.0])
    assert np.any(np.all(rig.vertices == vertex, axis=1))
    d = np.array([0.03, 0.0, 0.009])
    blades = [([p[0], 0.35, p[2]], [p[0], 0.0, p[2]]) for p in (vertex - d, vertex + d)]
    result = tear_stroke(rig, *blades, opening=opening)
    check_tear(rig, result, *blades, opening)
    through = np.flatnonzero(np.all(np.abs(result.points - vertex) <= 1e-12, axis=1))
    assert len(through) == 1 and result.kinds[through[0]] == VERTEX and result.split[through[0]]


@pytest.mark.parametrize("opening", [0.0, 0.002])
def test_tear_from_vertex_to_vertex_along_the_row(opening):
    """Both ends exactly on vertices of the row, two rings apart: the path is the two edges between,
    through the vertex in the middle, and nothing else is split."""
    rig = capsule_arm()
    blades = row_blade(6 * RING), row_blade(8 * RING)
    result = tear_stroke(rig, *blades, opening=opening)
    check_tear(rig, result, *blades, opening)
    assert result.kinds.tolist() == [VERTEX] * 3
    np.testing.assert_allclose(result.points[:, 0], [6 * RING, 7 * RING, 8 * RING], atol=1e-12)
    assert rig.n_faces == result.rig.n_faces                # no face was split: the slit runs on edges


# ---- tear: edges in the plane (the incision) ---------------------------------------------------
@pytest.mark.parametrize("opening", [0.0, 0.002])
@pytest.mark.parametrize("row, start, step", [("top", 0.1, 0.014), ("top", 2.9, -0.014), ("side", 0.1, 0.014)])
def test_tear_incision_along_a_row_in_small_strokes(opening, row, start, step):
    """The issue's repro: a straight incision along the capsule's row in strokes of 0.014 (the plane runs
    through the row's vertices and along its edges). It failed with TearPathError at stroke 33 (opening
    0), ran to the next vertex of the row and back (stroke 25) and then started a new slit; with an
    opening it left zero-area faces from the first stroke. Now 45 strokes continue one slit."""
    rig = capsule_arm()
    xs = start + step * np.arange(46)
    torn, results = incision(rig, xs, opening, row)
    assert len(results) == 45
    assert pieces(torn) == 1
    loops = tear_topology(torn).boundary_loops()
    assert len(loops) == 1                                   # one connected slit
    # the slit spans the whole incision: its ends are S_0 and the last S_(i+1)
    along = np.asarray(torn.vertices)[np.concatenate(loops)][:, 0]
    assert along.min() == pytest.approx(min(xs[0], xs[-1]), abs=1e-12)
    assert along.max() == pytest.approx(max(xs[0], xs[-1]), abs=1e-12)
    if opening == 0.0:
        # the slit's two sides: 2 x its length
        topo = tear_topology(torn)
        ends = np.asarray(torn.vertices)[topo.representative[topo.edges[topo.boundary_edges]]]
        length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).sum()
        assert length == pytest.approx(2 * abs(xs[-1] - xs[0]), rel=1e-9)


@pytest.mark.parametrize("opening", [0.0, 0.002])
@pytest.mark.parametrize("y", [1.0, 1.3, 0.0])
@pytest.mark.parametrize("step", [2.4, 0.2])
def test_tear_up_a_staircase_along_a_grid_plane(y, step, opening):
    """Up two steps of a staircase in the plane y = const, blade vertical: along a row of grid vertices
    and its edges (y = 1), across the treads' diagonals (y = 1.3), or along the top of the side wall,
    whose faces lie in the plane (y = 0); in one stroke, or in strokes of 0.2 whose blade meets the
    risers' top edges exactly. The path climbs the risers along their edges in the plane; one slit."""
    rig = staircase([[3, 3, 3], [2, 2, 2], [1, 1, 1]])
    xs = 2.8 - step * np.arange(round(2.4 / step) + 1)
    for i in range(len(xs) - 1):
        blades = ([xs[i], y, 5.0], [xs[i], y, 0.5]), ([xs[i + 1], y, 5.0], [xs[i + 1], y, 0.5])
        result = tear_stroke(rig, *blades, opening=opening)
        check_tear(rig, result, *blades, opening)
        assert not result.jumps.any() and (i == 0 or (result.kinds[0] == VERTEX and result.split[0]))
        assert np.abs(result.points[:, 1] - y).max() <= 1e-12
        rig = result.rig
    assert len(tear_topology(rig).boundary_loops()) == 1 and pieces(rig) == 1


@pytest.mark.parametrize("opening", [0.0, 0.002])
@pytest.mark.parametrize("seed", [0, 1])
def test_tear_incision_along_a_row_of_a_rotated_capsule(seed, opening):
    """The issue's incision on a rotated and shifted capsule: the row's vertices lie on the planes only
    up to rounding, and each welded vertex's one classification (``tol``) keeps the walk along the row:
    40 strokes continue one slit."""
    rot, shift = rotation(seed), np.array([2.0, -1.0, 0.5])
    rig = moved(capsule_arm(), rot, shift)
    x = 0.1
    for i in range(40):
        blades = [np.array(row_blade(x + d)) @ rot.T + shift for d in (0.0, 0.014)]
        result = tear_stroke(rig, *blades, opening=opening)
        check_tear(rig, result, *blades, opening)
        assert not result.jumps.any() and (i == 0 or (result.kinds[0] == VERTEX and result.split[0]))
        rig, x = result.rig, x + 0.014
    assert len(tear_topology(rig).boundary_loops()) == 1 and pieces(rig) == 1


# ---- tear: a face in the plane ------------------------------------------------------------------------
def _wall(rig, x=1.0):
    """The corners of the faces lying in the plane x = ``x``, (f, 3, 3)."""
    corners = np.asarray(rig.vertices)[np.asarray(rig.faces)]
    return corners[np.all(corners[:, :, 0] == x, axis=1)]


def _area(corners):
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()


def test_tear_along_the_top_of_a_wall_in_the_plane():
    """Strokes along the top edge of a staircase's riser (x = 1), blade vertical: the plane x = 1 holds
    the riser's faces. The path runs along the edge; the riser's faces are split only where the path's
    points lie on their top edge (no path through them, no sliver), and eight strokes continue one
    slit."""
    rig = staircase([[2, 2, 2, 2], [1, 1, 1, 1], [1, 1, 1, 1]])
    wall = _wall(rig)
    y, step = 0.3, 0.45
    for i in range(8):
        blades = ([1.0, y, 3.0], [1.0, y, 0.5]), ([1.0, y + step, 3.0], [1.0, y + step, 0.5])
        result = tear_stroke(rig, *blades)
        check_tear(rig, result, *blades, 0.0)
        assert np.all(result.points[:, 0] == 1.0) and np.all(result.points[:, 2] == 2.0)
        assert i == 0 or (result.kinds[0] == VERTEX and result.split[0])
        rig, y = result.rig, y + step
    after = _wall(rig)
    assert _area(after) == pytest.approx(_area(wall), rel=1e-12)
    old = {tuple(p) for p in wall.reshape(-1, 3)}
    assert all(p[2] == 2.0 for p in after.reshape(-1, 3) if tuple(p) not in old)     # on the top edge
    assert len(tear_topology(rig).boundary_loops()) == 1 and pieces(rig) == 1


@pytest.mark.parametrize("opening", [0.0, 0.01])
def test_tear_from_inside_a_face_in_the_plane(opening):
    """The second blade lies in the tread z = 1 (it meets the staircase at the tread's far edge): the
    plane is the tread's, and the first blade's hit is inside a face lying in it. Over the tread the
    section is the tread itself; the path goes straight from S_i to S_(i+1) across its faces (not round
    by their edges), with no sliver."""
    rig = staircase([[2, 2, 2], [1, 1, 1], [1, 1, 1]])
    blades = ([2.3, 1.4, 2.0], [2.3, 1.4, 0.5]), ([3.5, 1.6, 1.0], [2.0, 1.6, 1.0])
    result = tear_stroke(rig, *blades, opening=opening)
    check_tear(rig, result, *blades, opening)
    assert result.kinds[0] == FACE and VERTEX not in result.kinds
    s, t = result.points[0], result.points[-1]
    np.testing.assert_allclose(t, [3.0, 1.6, 1.0], atol=1e-12)
    for p in result.points:                                  # on the segment S_i S_(i+1)
        assert np.linalg.norm(np.cross(p - s, t - s)) <= 1e-12 and 0.0 <= (p - s) @ (t - s) <= (t - s) @ (t - s)


# ---- tear: the slit's own end on the plane -------------------------------------------------------------
def test_tear_from_the_end_of_a_slit_that_lies_in_the_plane():
    """The slit's end vertex and the slit itself lie in the next stroke's plane: going on continues the
    slit (from its end, no jump back along it); turning opens from the end too; going back over the slit
    has nothing to tear."""
    rig = capsule_arm()
    first = tear_stroke(rig, row_blade(0.3), row_blade(0.35))
    on = tear_stroke(first.rig, row_blade(0.35), row_blade(0.4))
    check_tear(first.rig, on, row_blade(0.35), row_blade(0.4), 0.0)
    assert on.kinds[0] == VERTEX and on.split[0] and not on.jumps.any()
    assert (on.points[:, 0] >= 0.35 - 1e-12).all()
    assert len(tear_topology(on.rig).boundary_loops()) == 1
    turn = ([0.35, 0.35 * np.cos(0.4), 0.35 * np.sin(0.4)], [0.35, 0.0, 0.0])
    turned = tear_stroke(first.rig, row_blade(0.35), turn)
    check_tear(first.rig, turned, row_blade(0.35), turn, 0.0)
    assert turned.kinds[0] == VERTEX and turned.split[0]
    assert len(tear_topology(turned.rig).boundary_loops()) == 1 and pieces(turned.rig) == 1
    with pytest.raises(TearPathError):
        tear_stroke(first.rig, row_blade(0.35), row_blade(0.3))


# ---- tear: random axis-aligned strokes on the grid ----------------------------------------------------
@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=25)
@given(row=st.sampled_from(["top", "side"]), ring=st.integers(2, 30),
       offset=st.one_of(st.sampled_from([0.0, 0.25, 0.5]), st.floats(0.0, 1.0)),
       step=st.one_of(st.sampled_from([RING, RING / 2, 0.014, 2 * RING]), st.floats(0.004, 0.2)),
       direction=st.sampled_from([1.0, -1.0]), strokes=st.integers(1, 5),
       opening=st.sampled_from([0.0, 0.0, 0.002]))
def test_random_axis_aligned_incisions(row, ring, offset, step, direction, strokes, opening):
    """Incisions along a row of the capsule from a random grid offset (often exactly on a vertex), in
    strokes of random length (often a multiple of the ring spacing): every stroke continues the slit
    along the row, within the swept region, with no sliver and no TearPathError."""
    xs = (ring + offset) * RING + direction * step * np.arange(strokes + 1)
    assume(0.02 <= xs.min() and xs.max() <= 2.98)          # on the cylinder
    torn, _ = incision(capsule_arm(), xs, opening, row)
    assert len(tear_topology(torn).boundary_loops()) == 1 and pieces(torn) == 1


STEPS = [[3, 3, 3, 3], [2, 2, 2, 2], [1, 1, 1, 1], [1, 1, 1, 1]]


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=25)
@given(y=st.one_of(st.sampled_from([0.0, 1.0, 2.0, 1.5, 4.0, 1e-9, 1e-6]), st.floats(0.0, 4.0)),
       x0=st.one_of(st.sampled_from([0.5, 1.0, 2.0, 3.0]), st.floats(0.1, 3.9)),
       step=st.one_of(st.sampled_from([0.25, 0.5, 1.0]), st.floats(0.05, 1.5)),
       direction=st.sampled_from([1.0, -1.0]), strokes=st.integers(1, 4), opening=st.sampled_from([0.0, 0.002]),
       across=st.booleans())
@example(y=1e-09, x0=0.5, step=0.125, direction=1.0, strokes=2, opening=0.0, across=False)
def test_random_axis_aligned_incisions_on_a_staircase(y, x0, step, direction, strokes, opening, across):
    """Incisions on a staircase in vertical grid planes (x = const or y = const, often through a row of
    vertices, along the side walls whose faces lie in them, or within rounding of one), up and down its
    steps, in strokes of random length: every stroke continues one slit, within the swept region, with
    no sliver and no face turned over. (Found: a path that went back along an edge to a corner and down
    a wall's diagonal when the straight way over the wall was shorter; a one-face path 1e-9 from the
    face's side that made a zero-area piece; the second stroke of a path 1e-9 from a wall, from the
    first stroke's end at a corner through a midpoint to an end inside the face, fanned from the
    midpoint: a zero-area piece; an opening of 0.002 along a path 0.001 from a wall's edge, which moved
    the far side onto the edge: zero-area and turned-over faces (the next test).)"""
    xs = x0 + direction * step * np.arange(strokes + 1)
    assume(0.05 <= xs.min() and xs.max() <= 3.95)
    rig = staircase(STEPS)

    def blade(x):
        return ([y, x, 5.0], [y, x, 0.5]) if across else ([x, y, 5.0], [x, y, 0.5])
    for i in range(strokes):
        blades = blade(xs[i]), blade(xs[i + 1])
        result = tear_stroke(rig, *blades, opening=opening)
        check_tear(rig, result, *blades, opening)
        assert opening == 0 or turned_over(rig, result, *blades) == 0
        assert not result.jumps.any() and (i == 0 or (result.kinds[0] == VERTEX and result.split[0]))
        rig = result.rig
    assert len(tear_topology(rig).boundary_loops()) == 1 and pieces(rig) == 1


@pytest.mark.parametrize("x0, step", [(0.5, 0.25), (2.0, -0.5)])
def test_opened_incision_closer_to_an_edge_than_half_the_opening(x0, step):
    """Two opened strokes in the plane y = 0.001, opening 0.002, along the staircase's front wall
    (y = 0): moving the far side by opening/2 put it on the wall's top edge, where the faces between
    them had zero area (along a tread: 2; over a riser's top, where the path passes 0.001 from the
    corner (1, 0, 2): 6, and the far side's copies there on that corner, which made non-manifold
    edges). The side with too little room moves less and the other more: still the whole opening
    apart, with no zero-area face and none turned over. (The staircase property test's case.)"""
    rig = staircase(STEPS)
    xs = x0 + step * np.arange(3)
    for i in range(2):
        blades = ([xs[i], 0.001, 5.0], [xs[i], 0.001, 0.5]), ([xs[i + 1], 0.001, 5.0], [xs[i + 1], 0.001, 0.5])
        result = tear_stroke(rig, *blades, opening=0.002)
        check_tear(rig, result, *blades, 0.002)
        assert turned_over(rig, result, *blades) == 0
        assert not result.jumps.any() and (i == 0 or (result.kinds[0] == VERTEX and result.split[0]))
        rig = result.rig
    assert len(tear_topology(rig).boundary_loops()) == 1 and pieces(rig) == 1


# ---- cut -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("cap", [False, True])
def test_cut_through_one_vertex(cap):
    """An oblique plane through one vertex of the capsule (and along none of its edges): that vertex is
    kept by both halves, no new vertex lies on it."""
    rig = capsule_arm()
    vertex = np.array([1.0, TOP_ROW, 0.0])
    result = cut_checked(rig, [1.0, 0.3, 0.2], vertex, cap)
    row = int(np.flatnonzero(np.all(rig.vertices == vertex, axis=1))[0])
    for src in result.sources:
        assert row in src
    assert np.linalg.norm(result.new_positions - vertex, axis=1).min() > 1e-3


@pytest.mark.parametrize("cap", [False, True])
@pytest.mark.parametrize("normal", [(0, 0, 1.0), (0, 1.0, 0), (0, 0, -1.0), (0, 1.0, 1.0)])
def test_cut_along_rows_of_edges(normal, cap):
    """Planes through the capsule's axis along its rows (z = 0, y = 0, and the 45° rows): every vertex
    they meet is a vertex of the mesh and every edge of those rows lies in them. No new vertex, no
    sliver, halves of equal area."""
    rig = capsule_arm()
    result = cut_checked(rig, normal, [1.5, 0.0, 0.0], cap)
    assert len(result.edge_t) == 0
    assert len(result.positive.faces) == len(result.negative.faces)


STAIRS = [[4, 3, 2, 2], [3, 3, 2, 1], [2, 1, 1, 1]]


@pytest.mark.parametrize("cap", [False, True])
@pytest.mark.parametrize("level", [1, 2, 3])
@pytest.mark.parametrize("up", [1.0, -1.0])
def test_cut_through_the_treads_of_a_staircase(level, up, cap):
    """Planes z = level contain whole treads (faces in the plane) beside the section: each tread goes,
    whole, to the half it bounds (the one below it), no face is split, and the caps close the halves
    round the treads."""
    rig = staircase(STAIRS)
    result = cut_checked(rig, [0, 0, up], [0, 0, level], cap)
    assert len(result.edge_t) == 0
    below = result.negative if up > 0 else result.positive
    corners = np.asarray(rig.vertices)[np.asarray(rig.faces)]
    treads = np.count_nonzero(np.all(corners[:, :, 2] == level, axis=1))
    kept = np.asarray(below.vertices)[np.asarray(below.faces)]
    assert treads > 0
    assert np.count_nonzero(np.all(kept[:, :, 2] == level, axis=1)) >= treads


def _grid_planes():
    planes = []
    size = (len(STAIRS), len(STAIRS[0]), max(map(max, STAIRS)))
    for axis in range(3):
        for level in range(1, size[axis]):
            planes.append((tuple(np.eye(3)[axis]), tuple(level * np.eye(3)[axis])))
    for normal, point in [((1, 1, -1), (3, 3, 1)), ((-1, -1, 1), (2, 1, 3)), ((1, 1, -1), (0, 3, 2)),
                          ((-1, 1, -1), (1, 0, 0)), ((1, 0, 1), (1, 0, 2)), ((1, -1, 0), (2, 1, 0))]:
        planes.append((tuple(float(c) for c in normal), tuple(float(c) for c in point)))
    return planes


@pytest.mark.parametrize("cap", [False, True])
@pytest.mark.parametrize("normal, point", _grid_planes())
def test_cut_a_staircase_along_grid_planes(normal, point, cap):
    """Every axis plane through the staircase's grid, and diagonal planes through its grid points (rows
    of vertices, edges and faces in the plane; the caps' loops with runs of collinear vertices, which
    once gave zero-area cap triangles): the cut's invariants hold, and no sliver anywhere."""
    cut_checked(staircase(STAIRS), normal, point, cap)       # (both halves non-empty: a miss would warn)


@pytest.mark.parametrize("seed", [0, 1])
def test_cut_a_rotated_staircase_along_its_grid_planes(seed):
    """The grid planes of a rotated staircase far from the origin: vertices, edges and faces lie in
    them only up to rounding; the same invariants hold (with and without caps)."""
    rot, shift = rotation(seed), np.array([100.0, -3.0, 7.0])
    rig = moved(staircase(STAIRS), rot, shift)
    for normal, point in _grid_planes():
        for cap in (False, True):
            cut_checked(rig, np.array(normal) @ rot.T, np.array(point) @ rot.T + shift, cap)
