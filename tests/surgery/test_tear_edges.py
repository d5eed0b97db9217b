"""The tear at its edges (issue 43, part C): a stroke across an opened slit stays on the side the
blade swept (item 9), a blade near a slit's tip continues the slit wherever the pose carried the tip
(item 10; the session's ``continue_slit`` in test_session.py), and a tear plane along mesh edges makes
no repeated path point and no face of near-zero area (item 11).

Oracles: the blade's own geometry (the capsule's far side lies beyond the blade's tips, below its
axis), the hull of the blade positions widened by the stroke's margin (``tests.helpers.swept_region``),
the number of connected pieces of the welded mesh, and face areas computed with numpy.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import cgaskin
from cgaskin import TearPathError, capsule_arm, tear_stroke
from cgaskin.surgery.tear import tear_topology

from tests.helpers import grid_meshes
from tests.helpers.swept_region import hull_distance, margin
from tests.helpers.tear_checks import pieces

_CAPSULE = capsule_arm()


def vertical(x, y):
    """A vertical blade over the capsule arm: handle at z = 1 above it, tip on its axis (z = 0)."""
    return np.array([[x, y, 1.0], [x, y, 0.0]])


def check_on_the_swept_side(rig, result, scalpel_from, scalpel_to):
    """The path of a stroke whose blades reach down to the arm's axis (z = 0) stays above it (the far
    side of the arm is below it: the blade never touched it), within the swept region (the hull of
    the blade positions widened by the stroke's margin), and no longer than the region allows; the arm
    stays in one piece."""
    points = result.points
    assert points[:, 2].min() > 0.0, f"the path runs under the arm: z down to {points[:, 2].min():.3g}"
    blades = np.array([scalpel_from, scalpel_to], np.float64)
    bvh = cgaskin.TriangleBVH(np.asarray(rig.vertices), np.asarray(rig.faces))
    hit_faces = [bvh.first_hit(*blade)[0] for blade in blades]
    widened = margin(rig.vertices, rig.faces, hit_faces, points[0], points[-1])
    assert max(hull_distance(p, blades) for p in points) <= widened * (1 + 1e-9)
    length = np.linalg.norm(np.diff(points, axis=0), axis=1).sum()
    assert length <= np.linalg.norm(points[-1] - points[0]) + 2 * widened
    assert pieces(result.rig) == 1


@pytest.mark.parametrize("opening", [0.001, 0.002, 0.01, 0.05])
def test_the_issues_stroke_across_an_opened_slit_crosses_it(opening):
    """Issue 43 item 9: the second stroke ran under the arm (z down to -0.25, 1.38 long where the blade
    swept 0.18) for every opening >= 0.002; it crosses the opened gap as the closed slit's X junction."""
    first = tear_stroke(_CAPSULE, vertical(1.0, .05), vertical(1.5, .05), opening=opening)
    across = tear_stroke(first.rig, vertical(1.25, -.05), vertical(1.25, .12), opening=opening)
    check_on_the_swept_side(first.rig, across, vertical(1.25, -.05), vertical(1.25, .12))
    assert across.jumps.sum() == 1                         # through the gap, once
    assert across.split[1:-1].all()


@pytest.mark.parametrize("scalpel_from, scalpel_to", [((1.92, 0.06), (1.84, -0.12)), ((1.91, 0.07), (1.85, -0.13)),
                                                      ((1.93, 0.08), (1.86, -0.12))])
def test_a_stroke_across_a_slit_opened_as_wide_as_the_faces(scalpel_from, scalpel_to):
    """A slit opened by 0.08, about the size of the capsule's faces: thin faces beside it fold over the gap,
    where the section cannot jump across, and the path ran round under the arm. It crosses the gap, or
    raises TearPathError."""
    first = tear_stroke(_CAPSULE, vertical(1.75, 0.04), vertical(2.05, -0.09), opening=0.08)
    blades = vertical(*scalpel_from), vertical(*scalpel_to)
    try:
        across = tear_stroke(first.rig, *blades, opening=0.08)
    except TearPathError:
        return
    check_on_the_swept_side(first.rig, across, *blades)


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=25)
@given(y=st.floats(-0.12, 0.12), x0=st.floats(0.5, 1.2), span=st.floats(0.3, 1.0),
       opening=st.floats(0.0, 0.04), at=st.one_of(st.floats(0.05, 0.95), st.integers(1, 30)),
       slant=st.one_of(st.just(0.0), st.floats(-0.03, 0.03)), below=st.floats(0.02, 0.1),
       above=st.floats(0.02, 0.1))
def test_random_strokes_across_opened_slits_stay_on_the_swept_side(y, x0, span, opening, at, slant, below, above):
    """A slit along the top of the capsule arm, opened by a random amount, then a stroke across it at a
    random place -- often exactly through a vertex of the slit (``at`` an integer: where the issue's
    stroke went round), the blade slanted a little: the path stays on the side the blade swept (or the
    stroke raises TearPathError), never round the far side."""
    first = tear_stroke(_CAPSULE, vertical(x0, y), vertical(x0 + span, y), opening=opening)
    if isinstance(at, int):
        inner = first.points[1:-1]
        x = float(inner[at % len(inner), 0])
    else:
        x = x0 + at * span
    # (each blade off the gap, which is ``opening`` wide)
    blades = (vertical(x - slant, y - opening - below), vertical(x + slant, y + opening + above))
    try:
        across = tear_stroke(first.rig, *blades, opening=opening)
    except TearPathError:
        return
    check_on_the_swept_side(first.rig, across, *blades)


# ---- item 11: a tear plane along mesh edges ---------------------------------------------------------------
#: the README's Fox stroke
FOX_FROM, FOX_TO = ([0, 120, 0], [0, 40, 0]), ([0, 120, 10], [0, 40, 10])


def skinned_areas(rig, pose) -> np.ndarray:
    points = cgaskin.skin(rig, pose) if pose is not None else np.asarray(rig.vertices, np.float64)
    corners = points[np.asarray(rig.faces)]
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)


def check_no_slivers(result, pose, diagonal):
    """No path point repeats the previous one (closer than 1e-9 of the diagonal), and no face of the torn
    rig has an area below 1e-12 of the diagonal squared (the issue's had 3e-18)."""
    steps = np.linalg.norm(np.diff(result.points, axis=0), axis=1)
    assert steps.min() > 1e-9 * diagonal, f"a path point repeats: steps {np.sort(steps)[:3] / diagonal} of D"
    areas = skinned_areas(result.rig, pose)
    assert areas.min() > 1e-12 * diagonal ** 2, f"a face of area {areas.min() / diagonal ** 2:.3g} D^2"


@pytest.fixture(scope="module")
def fox(models_dir):
    return cgaskin.load(models_dir / "Fox.glb")


@pytest.mark.parametrize("opening", [0.0, 0.5])
def test_the_readme_fox_stroke_in_the_rest_pose_makes_no_sliver(fox, opening):
    """Issue 43 item 11: torn with ``pose=fox.rest_pose()`` the README's stroke (along Fox's symmetry
    plane, where a vertex lies 2e-9 of the diagonal off the plane once skinned) repeated one path point
    three times: 1742 vertices instead of 1732, two faces of area 3e-18 D^2. It runs through that vertex,
    as the stroke on the stored vertices does."""
    pose = fox.rest_pose()
    posed = tear_stroke(fox, FOX_FROM, FOX_TO, opening=opening, pose=pose)
    stored = tear_stroke(fox, FOX_FROM, FOX_TO, opening=opening)
    diagonal = float(np.linalg.norm(np.ptp(cgaskin.skin(fox, pose), axis=0)))
    check_no_slivers(posed, pose, diagonal)
    assert posed.rig.n_vertices == stored.rig.n_vertices == 1732
    assert posed.kinds.tolist() == stored.kinds.tolist()


def _noisy(rig, relative, seed):
    """``rig`` with every vertex moved by up to ``relative`` of its diagonal (the rounding of float32 data
    skinned through float32 matrices), each copy of a position alike."""
    vertices = np.asarray(rig.vertices, np.float64)
    diagonal = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    unique, inverse = np.unique(vertices, axis=0, return_inverse=True)
    shift = np.random.default_rng(seed).uniform(-1.0, 1.0, unique.shape) * relative * diagonal
    return rig._with_checked_mesh(vertices + shift[inverse.reshape(-1)], rig.faces, rig.joints, rig.weights,
                                  dict(rig.attributes))


_BOX = grid_meshes.voxel_rig(np.ones((4, 4, 2), bool))


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=30)
@given(along=st.sampled_from(["x", "diagonal"]), line=st.integers(1, 3), start=st.floats(0.0, 1.0),
       end=st.floats(0.0, 1.0), noise=st.floats(1e-9, 9e-9), seed=st.integers(0, 2 ** 16),
       opening=st.sampled_from([0.0, 0.05]))
def test_tear_planes_along_grid_edges_with_rounded_vertices(along, line, start, end, noise, seed, opening):
    """A stroke on top of a box of voxels (4 x 4 x 2) in a plane that holds rows of its edges (a grid line
    y = line, or a diagonal of the top's squares x - y = line - 2), its vertices moved by float32-like
    rounding (up to 9e-9 of the diagonal): the path runs through the rows' vertices as on the exact grid
    (the same vertices made), no path point repeats and no face has near-zero area."""
    offset = 0.0 if along == "x" else line - 2.0
    lo, hi = max(0.1, 0.1 - offset), min(3.9, 3.9 - offset)      # the stretch of the line on the top
    ends = []
    for f in (start, end):
        t = lo + f * (hi - lo)
        ends.append(np.array([t, line, 2.0]) if along == "x" else np.array([t + offset, t, 2.0]))
    if np.linalg.norm(ends[1] - ends[0]) < 0.2:
        return
    blades = [np.array([e + [0, 0, 3.0], e - [0, 0, 1.0]]) for e in ends]
    try:
        reference = tear_stroke(_BOX, *blades, opening=opening)
    except TearPathError:
        return
    noisy = _noisy(_BOX, noise, seed)
    result = tear_stroke(noisy, *blades, opening=opening)
    diagonal = float(np.linalg.norm(np.ptp(np.asarray(noisy.vertices), axis=0)))
    check_no_slivers(result, None, diagonal)
    assert result.rig.n_vertices == reference.rig.n_vertices
    assert result.kinds.tolist() == reference.kinds.tolist()


# ---- item 10: a stroke near the slit's tip continues the slit --------------------------------------------------
_ARM = capsule_arm(rings_per_segment=40, segments_around=32)


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=20)
@given(t=st.floats(0.0, 0.3), angle=st.floats(0.0, 2 * np.pi), within=st.floats(0.0, 0.95),
       opening=st.sampled_from([0.0, 0.002, 0.02]))
def test_a_blade_within_reach_of_the_tip_continues_the_slit(t, angle, within, opening):
    """A slit torn at rest, then a stroke in a pose of the clip whose blade at t_i passes within
    max(opening, 1e-3 of the diagonal) of where that pose carries the slit's tip (in any direction across
    the blade): the stroke starts at the tip and continues the slit (one slit, split there); a blade
    twice that far starts a slit of its own."""
    first = tear_stroke(_ARM, vertical(0.5, 0.03), vertical(0.6, 0.03), opening=opening)
    pose = _ARM.pose("wave", t)
    skinned = cgaskin.skin(first.rig, pose)
    tip = skinned[first.side_a[-1]]
    reach = max(opening, 1e-3 * float(np.linalg.norm(np.ptp(skinned, axis=0))))
    aside = np.array([np.cos(angle), np.sin(angle), 0.0])
    ahead = skinned[np.argmin(np.linalg.norm(skinned - (tip + [0.1, 0.0, 0.0]), axis=1))]
    scalpel_to = np.array([ahead + [0, 0, 0.3], ahead - [0, 0, 0.05]])
    near = tip + within * reach * aside
    result = tear_stroke(first.rig, [near + [0, 0, 0.3], near - [0, 0, 0.05]], scalpel_to, pose=pose,
                         opening=opening)
    assert result.split[0] and np.array_equal(result.points[0], tip)
    assert len(tear_topology(result.rig).boundary_loops()) == 1
    far = tip + 2.0 * reach * aside
    try:
        apart = tear_stroke(first.rig, [far + [0, 0, 0.3], far - [0, 0, 0.05]], scalpel_to, pose=pose,
                            opening=opening)
    except (TearPathError, cgaskin.MissesMeshError):
        return
    assert not np.array_equal(apart.points[0], tip)
