"""Plane cuts (cgaskin.cut) of the shared models (Arm5, 3Cylinder4bones, Fox), the procedural capsule
arm and random closed skinned meshes with attribute seams, by random planes (through random points of
the bounding box and through vertices), at rest and posed, capped or not: every invariant of
``tests.helpers.cut_checks.check_cut``, and with caps the halves' volumes add up.
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import cgaskin
from cgaskin import cut_details

from tests.helpers.cut_checks import (AREA, MODELS, check_cut, crossing, diagonal, model, normals,
                                      plane_points, random_closed_rig, random_pose, volume)


fixture_settings = settings(suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                   HealthCheck.too_slow])


# ---- property tests -----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", MODELS + ["capsule"])
@fixture_settings
@given(data=st.data(), normal=normals, cap=st.booleans())
def test_rest_cut_of_models(models_dir, name, data, normal, cap):
    rig = model(models_dir, name)
    point = data.draw(plane_points(rig.vertices))
    if not crossing(rig, normal, point):
        return
    result = cut_details(rig, normal, point, cap=cap)
    closed = name in ("Fox.glb", "3Cylinder4bones.glb", "capsule")
    check_cut(rig, result, closed=closed, capped=cap)
    if cap and closed:
        total = volume(result.positive.vertices, result.positive.faces) + volume(result.negative.vertices,
                                                                                  result.negative.faces)
        assert total == pytest.approx(volume(rig.vertices, rig.faces), rel=AREA)


@pytest.mark.parametrize("name", MODELS + ["capsule"])
@fixture_settings
@given(data=st.data(), normal=normals, seed=st.integers(0, 2 ** 32 - 1), cap=st.booleans())
def test_posed_cut_of_models(models_dir, name, data, normal, seed, cap):
    rig = model(models_dir, name)
    rng = np.random.default_rng(seed)
    pose = rig.pose(0, rng.uniform(0, rig.clips[0].duration)) if rig.clips and seed % 2 else random_pose(rig, rng)
    posed = cgaskin.skin(rig, pose)
    point = data.draw(plane_points(posed))
    if not crossing(rig, normal, point, pose):
        return
    result = cut_details(rig, normal, point, pose=pose, cap=cap)
    assert result.residual <= 1e-12 * diagonal(posed)
    closed = name in ("Fox.glb", "3Cylinder4bones.glb", "capsule")
    check_cut(rig, result, pose=pose, closed=closed, capped=cap)
    if cap and closed:
        halves = [cgaskin.skin(h, pose) for h in (result.positive, result.negative)]
        total = sum(volume(p, h.faces) for p, h in zip(halves, (result.positive, result.negative)))
        assert total == pytest.approx(volume(posed, rig.faces), rel=1e-9)


@settings(deadline=None)
@given(shape=st.sampled_from(["sphere", "torus", "box", "capsule"]), seed=st.integers(0, 2 ** 32 - 1),
       split=st.sampled_from([0.0, 0.3, 1.0]), normal=normals, data=st.data(), posed=st.booleans(),
       cap=st.booleans())
def test_cut_of_random_skinned_meshes(shape, seed, split, normal, data, posed, cap):
    rig = random_closed_rig(shape, seed, split)
    pose = random_pose(rig, np.random.default_rng(seed + 1), max_angle=0.3) if posed else None
    positions = cgaskin.skin(rig, pose) if posed else rig.vertices
    point = data.draw(plane_points(positions))
    if not crossing(rig, normal, point, pose):
        return
    result = cut_details(rig, normal, point, pose=pose, cap=cap)
    check_cut(rig, result, pose=pose, closed=True, capped=cap)
    if cap:
        halves = [cgaskin.skin(h, pose) if posed else h.vertices for h in (result.positive, result.negative)]
        total = sum(volume(p, h.faces) for p, h in zip(halves, (result.positive, result.negative)))
        assert total == pytest.approx(volume(positions, rig.faces), rel=1e-9)
