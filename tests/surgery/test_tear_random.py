"""The scalpel tear (cgaskin.tear_stroke) by random strokes over real and procedural rigs, at rest and
posed, closed or opened, one stroke or two that make one slit: every invariant of
``tests.helpers.tear_checks.check_stroke``; torn rigs skin, animate and export like the original.
When the tear reports that the plane's section does not lead from S_i to S_{i+1}, an independent
check (connected pieces of the section within the swept region, by brute force over all faces) must
agree; a path never leaves that region (``tests.helpers.swept_region``).
"""
from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from cgaskin import TearPathError, TriangleBVH, tear_stroke
from cgaskin.surgery.tear.patch import patch_surface
from cgaskin.surgery.tear.rig_source import RigSource
from cgaskin.surgery.tear import tear_topology
from cgaskin.surgery.tear.locate import locate

from tests.helpers.tear_checks import (check_like_original, check_stroke, diagonal, face_normal, save_gltf,
                                       section_separates, some_pose, some_tear, strokes, surface)
from tests.helpers.swept_region import hull_distance, margin


# ---- random strokes ------------------------------------------------------------------------------------
def run_random_stroke(name, rig, pose, data, opening=0.0):
    points = surface(rig, pose)
    scalpel_from, scalpel_to = data.draw(strokes(rig, points))
    original = copy.deepcopy((rig.vertices, rig.faces, rig.joints, rig.weights, rig.attributes))
    blades = np.asarray(scalpel_from, np.float64), np.asarray(scalpel_to, np.float64)
    # the whole mesh in the pose (a BVH of the whole skinned surface: a posed stroke itself poses only
    # what its blade reaches)
    whole = patch_surface(RigSource(rig, pose, None if pose is None else TriangleBVH(points, rig.faces)),
                          np.arange(rig.n_faces)).surface
    ends = locate(whole, whole.faces, *blades[0], *blades[1])
    within = blades, margin(points, rig.faces, ends.hit_faces, *ends.points)
    try:
        result = tear_stroke(rig, scalpel_from, scalpel_to, pose=pose, opening=opening)
    except TearPathError:
        # legitimate only when the section within the swept region really does not join the two hits
        assert section_separates(rig, ends.plane, blades, pose, within) in (True, None)
        return None
    for before, after in zip(original, (rig.vertices, rig.faces, rig.joints, rig.weights)):
        np.testing.assert_array_equal(before, after)        # the caller's rig is not modified
    check_stroke(rig, result, pose, opening)
    # the path never leaves the region the blade swept (no detour)
    assert max(hull_distance(p, blades) for p in result.points) <= within[1] * (1 + 1e-9)
    return result


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(data=st.data())
def test_random_strokes_at_rest(tear_model, data):
    name, rig = tear_model
    result = run_random_stroke(name, rig, None, data)
    if result is not None:
        check_like_original(rig, result.rig, some_pose(name, rig))


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(data=st.data())
def test_random_strokes_posed(tear_model, data):
    """Posed tears: intersections and walk in the pose; new vertices placed through their inverse
    blended transforms land exactly on the posed path when the torn rig is skinned."""
    name, rig = tear_model
    pose = some_pose(name, rig)
    result = run_random_stroke(name, rig, pose, data)
    if result is not None:
        check_like_original(rig, result.rig, pose)


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None,
          max_examples=20)
@given(data=st.data(), opening=st.floats(1e-4, 0.02), posed=st.booleans())
def test_random_strokes_with_opening(tear_model, data, opening, posed):
    name, rig = tear_model
    pose = some_pose(name, rig) if posed else None
    run_random_stroke(name, rig, pose, data, opening=opening * diagonal(surface(rig, pose)))


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None,
          max_examples=25)
@given(data=st.data(), posed=st.booleans(), opening=st.sampled_from([0.0, 0.0, 0.004]))
def test_two_strokes_make_one_slit(tear_model, data, posed, opening):
    """The second stroke starts where the first ended (same blade): it continues the same slit, so
    a closed surface gets exactly one boundary loop, made of both paths on both sides -- also when
    the slits are opened (the blade then meets the tip of the first slit's gap)."""
    name, rig = tear_model
    pose = some_pose(name, rig) if posed else None
    points = surface(rig, pose)
    opening *= diagonal(points)
    scalpel_from, scalpel_to = data.draw(strokes(rig, points))
    try:
        first = tear_stroke(rig, scalpel_from, scalpel_to, pose=pose, opening=opening)
    except TearPathError:
        return
    torn = first.rig
    # the third blade: through a surface point near where the first stroke ended
    after = surface(torn, pose)
    end = first.points[-1]
    faces = np.asarray(torn.faces)
    dist = np.linalg.norm(after[faces].mean(axis=1) - end, axis=1)
    near = np.flatnonzero((dist < 0.03 * diagonal(after)) & (dist > 0.005 * diagonal(after)))
    assume(len(near) > 0)
    f = int(near[data.draw(st.integers(0, len(near) - 1))])
    w = np.array(data.draw(st.tuples(*[st.floats(0.05, 1.0)] * 3)))
    p = (w / w.sum()) @ after[faces[f]]
    h = 0.02 * diagonal(after) * face_normal(after, faces[f])
    try:
        second = tear_stroke(torn, scalpel_to, np.array([p + h, p - h]), pose=pose, opening=opening)
    except TearPathError:
        return
    assert second.kinds[0] == 0                      # it starts at the first stroke's end vertex
    np.testing.assert_allclose(second.points[0], end, rtol=0, atol=1e-12 * diagonal(after))
    check_stroke(torn, second, pose, opening)
    assert second.split[0]                           # the old end opens: the slits join
    topo = tear_topology(second.rig)
    if len(tear_topology(rig).boundary_edges) == 0 and not second.jumps.any():
        # (a second stroke that crosses the first slit cuts out the piece between them: checked by
        # tests/surgery/test_tear_junctions.py)
        loops = topo.boundary_loops()
        assert len(loops) == 1
        assert len(loops[0]) == 2 * (len(first.points) - 1) + 2 * (len(second.points) - 1)


@pytest.mark.skipif(save_gltf is None, reason="cgaskin.rigs.export is not available")
def test_torn_rigs_export_and_reload(tear_model, tmp_path):
    name, rig = tear_model
    pose = some_pose(name, rig)
    for result in (some_tear(rig), some_tear(rig, pose, seed=1)):
        check_like_original(rig, result.rig, pose, tmp_path)
