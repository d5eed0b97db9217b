"""A stroke meets an existing slit (issue 10, item 2): it never detours round it. The new slit crosses
the old one (an X junction) or ends on it (a T junction), the path stays in the region the blade swept,
and a stroke with nothing left to tear says so.

Oracles: the path's distance from the hull of the blade positions (``tests.helpers.swept_region``), the
number of connected pieces of the welded mesh, and the boundary loops of the torn surface.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from cgaskin import TearPathError, capsule_arm, load, tear_stroke
from cgaskin.surgery.tear import tear_topology

from tests.helpers.swept_region import hull_distance
from tests.helpers.tear_checks import pieces

FOX_A = ([0.3, 120, 0.7], [0.3, 40, 0.7])
FOX_B = ([0.3, 120, 10.1], [0.3, 40, 10.1])
ACROSS = (([-6, 120, 5], [-6, 40, 5]), ([6, 120, 5.5], [6, 40, 5.5]))


def max_outside(result, scalpel_from, scalpel_to) -> float:
    """How far the path leaves the hull of the blade positions, relative to the stroke's length."""
    blades = np.array([scalpel_from, scalpel_to], np.float64)
    stroke = np.linalg.norm(result.points[-1] - result.points[0])
    return max(hull_distance(p, blades) for p in result.points) / stroke


@pytest.fixture(scope="module")
def fox(models_dir):
    return load(models_dir / "Fox.glb")


@pytest.mark.parametrize("opening", [0.0, 0.5])
def test_the_same_stroke_twice_has_nothing_to_tear(fox, opening):
    """The issue's repro: the second application gave a 35-point path from nose to tail and two pieces."""
    first = tear_stroke(fox, FOX_A, FOX_B, opening=opening)
    assert len(first.points) == 5
    with pytest.raises(TearPathError):
        tear_stroke(first.rig, FOX_A, FOX_B, opening=opening)


@pytest.mark.parametrize("opening", [0.0, 0.5])
def test_a_stroke_across_a_slit_crosses_it(fox, opening):
    """X junction: the path crosses the slit on the back (it ran under the belly before), the fox stays
    in one piece, and the two slits open into one hole (one boundary loop)."""
    first = tear_stroke(fox, FOX_A, FOX_B, opening=opening)
    across = tear_stroke(first.rig, *ACROSS, opening=opening)
    assert across.points[:, 1].min() > 55                   # on the back: the belly is below y = 40
    assert max_outside(across, *ACROSS) < 1.0
    assert pieces(across.rig) == pieces(fox) == 1
    loops = tear_topology(across.rig).boundary_loops()
    assert len(loops) == len(tear_topology(fox).boundary_loops()) + 1
    # the crossing: two path points on the old slit's two sides, split, both within the opening
    assert across.split[1:-1].all() and not across.split[0] and not across.split[-1]


@pytest.mark.parametrize("opening", [0.0, 0.5])
def test_a_stroke_that_ends_on_a_slit_joins_it(fox, opening):
    """T junction: a stroke from the side to the slit ends on it, and opens into it."""
    first = tear_stroke(fox, FOX_A, FOX_B, opening=opening)
    side = first.rig.vertices[first.side_a[2]]               # a vertex of the slit's near side
    to = ([side[0], 120, side[2]], [side[0], 40, side[2]])
    t = tear_stroke(first.rig, ACROSS[0], to, opening=opening)
    assert np.linalg.norm(t.points[-1] - side) < 1.0
    assert t.split[-1]                                       # the end on the slit opens into it
    assert pieces(t.rig) == 1
    assert len(tear_topology(t.rig).boundary_loops()) == len(tear_topology(fox).boundary_loops()) + 1


@settings(suppress_health_check=[HealthCheck.too_slow], deadline=None, max_examples=30)
@given(x=st.floats(0.6, 2.4), angle=st.floats(-1.2, 1.2), length=st.floats(0.08, 0.4),
       opening=st.sampled_from([0.0, 0.0, 0.01]))
def test_random_strokes_across_a_slit_of_the_capsule(x, angle, length, opening):
    """Strokes at random angles across a slit along the top of the capsule arm: each crosses it
    within the swept region and keeps the arm in one piece, or reports a TearPathError."""
    rig = capsule_arm()
    slit = tear_stroke(rig, ([0.5, 1, 0.02], [0.5, -1, 0.02]), ([2.5, 1, 0.03], [2.5, -1, 0.03]),
                       opening=opening)
    d = 0.5 * length * np.array([np.sin(angle), 0.0, np.cos(angle)])
    centre = np.array([x, 0.0, 0.025])
    blades = [np.array([c + [0, 1, 0], c - [0, 1, 0]]) for c in (centre - d, centre + d)]
    try:
        across = tear_stroke(slit.rig, *blades, opening=opening)
    except TearPathError:
        return
    assert max_outside(across, *blades) < 1.0
    assert pieces(across.rig) == 1


@pytest.mark.parametrize("opening", [0.0, 0.002])
def test_an_incision_along_a_row_of_vertices_never_runs_back_along_its_slit(opening):
    """Small strokes along the top of the capsule, in a plane through its row of vertices and edges
    (issue 13's degenerate family): the two sides of the closed slit lie in the plane, and a path may
    not jump between them (it ran back along the slit). Each stroke tears without a jump and within
    the swept region, or raises TearPathError. (That a path here may still overshoot to the next
    vertex of the row and come back inside the region is the exact handling of such planes, issue 13.)"""
    rig, x = capsule_arm(), 0.1
    blade = ([x, 0.35, 0.0], [x, 0.0, 0.0])
    for _ in range(40):
        following = ([x + 0.014, 0.35, 0.0], [x + 0.014, 0.0, 0.0])
        try:
            result = tear_stroke(rig, blade, following, opening=opening)
        except TearPathError:
            assert opening == 0.0                    # the opened slit never meets the degenerate case
            return
        assert not result.jumps.any()
        corners = rig.vertices[rig.faces]
        longest = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max()   # bounds the margin
        assert max_outside(result, blade, following) * 0.014 <= 0.014 + longest
        rig, blade, x = result.rig, following, x + 0.014
