"""The tear at its edges (issue 43, part C): a stroke across an opened slit stays on the side the
blade swept (item 9).

Oracles: the blade's own geometry (the capsule's far side lies beyond the blade's tips, below its
axis), the hull of the blade positions widened by the stroke's margin (``tests.helpers.swept_region``),
and the number of connected pieces of the welded mesh.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import cgaskin
from cgaskin import TearPathError, capsule_arm, tear_stroke

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
