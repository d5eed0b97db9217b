"""Numbers given where numbers belong: strings are refused (numpy would parse "2" as 2.0), dilations
outside what float64 holds are refused where they are given, a NaN vertex is named by its row
negative weights are refused (issue 10, "clear errors")."""
import dataclasses

import numpy as np
import pytest

import cgaskin
from cgaskin import versor
from cgaskin.errors import InvalidInputError

STROKE = (([0.6, 0.5, 0.0], [0.6, 0.0, 0.0]), ([0.9, 0.5, 0.0], [0.9, 0.0, 0.0]))


@pytest.mark.parametrize("scale", [1e20, 1e13, 0.0, -1.0, 1e-13])
def test_dilation_outside_the_range_is_refused_where_it_is_given(scale):
    pose = cgaskin.capsule_arm().rest_pose()
    with pytest.raises(InvalidInputError, match=r"scale must lie in \[1e-12, 1e\+12\]"):
        pose.dilate(1, scale)


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1e6, 1e12])
def test_dilations_inside_the_range_skin(scale):
    rig = cgaskin.capsule_arm()
    out = cgaskin.skin(rig, rig.rest_pose().dilate(1, scale))
    assert np.isfinite(out).all()


@pytest.mark.parametrize("call", [
    lambda rig: rig.rest_pose().dilate(1, "2"),
    lambda rig: rig.rest_pose().translate(1, ["1", 0, 0]),
    lambda rig: rig.rest_pose().rotate(1, [0, 0, 1], "0.5"),
    lambda rig: rig.pose("wave", "0.3"),
    lambda rig: cgaskin.tear(rig, *STROKE, opening="0.5"),
    lambda rig: cgaskin.cut(rig, ["1", 0, 0], [1.5, 0, 0]),
    lambda rig: versor.motor([0, 0, 1], 0.5, ["1", "0", "0"]),
    lambda rig: rig.pose("wave", True),
], ids=["dilate", "translate", "rotate", "pose time", "opening", "cut normal", "motor", "bool time"])
def test_strings_are_not_numbers(call):
    with pytest.raises(InvalidInputError):
        call(cgaskin.capsule_arm())


@pytest.mark.parametrize("operation", ["cut", "tear"])
def test_a_nan_vertex_is_named_by_its_row(operation):
    rig = cgaskin.capsule_arm()
    vertices = rig.vertices.copy()
    vertices[123, 1] = np.nan
    # refused where the rig is made (issue 22), before any operation can see it
    with pytest.raises(InvalidInputError, match=r"vertex 123 has a non-finite position \[[-0-9.e]+, nan, "):
        bad = dataclasses.replace(rig, vertices=vertices)
        cgaskin.cut(bad, [1, 0, 0], [1.5, 0, 0]) if operation == "cut" else cgaskin.tear(bad, *STROKE)


@pytest.mark.parametrize("parallel", [False, True])
def test_negative_weights_are_refused_naming_the_vertex(parallel):
    rig = cgaskin.capsule_arm()
    weights = np.array(rig.weights)
    weights[7, :2] = [1.5, -0.5]                   # sums to 1, but is no blend
    versors = np.tile(versor.motor([0, 0, 1], 0.3, [0, 0, 0]), (rig.skeleton.n_bones, 1))
    before = weights.copy()
    with pytest.raises(InvalidInputError, match=r"weights must be >= 0.*vertex 7 has weight -0.5 on influence 1"):
        cgaskin.skin_vertices(rig.vertices, rig.joints, weights, versors, parallel=parallel)
    np.testing.assert_array_equal(weights, before)
