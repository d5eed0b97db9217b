"""The editing session ``cgaskin.Surgery``: after any sequence of operations its mesh is what the
functional API gives after the same operations (same faces, positions to 1e-12 of the model's size,
weights, attributes, tear labels), the caller's rig and earlier snapshots never change, undo takes an
operation back exactly, a failed operation changes nothing, and a session continues from a saved file.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st

import cgaskin
from cgaskin import InvalidInputError, MissesMeshError, Surgery, TearPathError
from cgaskin.surgery.tear import TEAR_LABEL, tear_topology

from tests.helpers.tear_checks import diagonal, pieces, some_pose, strokes, surface

SETTINGS = dict(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
                deadline=None)
#: what a stroke may raise on a random blade: the same error from the session and the functional API
STROKE_ERRORS = (TearPathError, MissesMeshError, InvalidInputError)


def assert_same_mesh(a, b, scale):
    """Two rigs hold the same mesh: faces, joints and weights equal, positions and attributes to 1e-12
    of ``scale`` (they are equal bit for bit today; the tolerance is the promise)."""
    np.testing.assert_array_equal(np.asarray(a.faces), np.asarray(b.faces))
    np.testing.assert_allclose(a.vertices, b.vertices, rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(a.joints, b.joints)
    np.testing.assert_allclose(a.weights, b.weights, rtol=0, atol=1e-12)
    assert a.attributes.keys() == b.attributes.keys()
    for name in a.attributes:
        np.testing.assert_allclose(a.attributes[name], b.attributes[name], rtol=0, atol=1e-12 * max(scale, 1))


def boundary_of(rig) -> np.ndarray:
    """(n,) bool the vertices on a boundary edge of the rig's whole welded topology, built anew."""
    topo = tear_topology(rig)
    on_boundary = np.zeros(topo.n_welded, bool)
    on_boundary[topo.edges[topo.boundary_edges].reshape(-1)] = True
    return on_boundary[topo.welded]


def assert_same_boundary(session, rig):
    """The session's boundary flags, updated stroke by stroke, are those of the whole mesh built anew."""
    expected = boundary_of(rig)
    np.testing.assert_array_equal(session.boundary, expected)


def _stroke_after(last, draw, rig, pose):
    """A random stroke (``strokes``); half the time moved to continue the previous one (its blade at
    t_i is the last stroke's blade at t_(i+1))."""
    scalpel_from, scalpel_to = (np.asarray(b, float) for b in draw(strokes(rig, surface(rig, pose))))
    if last is not None and draw(st.booleans()):
        scalpel_from, scalpel_to = last, last + (scalpel_to - scalpel_from)
    return scalpel_from, scalpel_to


@settings(max_examples=12, **SETTINGS)
@given(data=st.data(), posed=st.booleans())
def test_session_equals_the_functional_chain(tear_model, data, posed):
    name, rig = tear_model
    pose = some_pose(name, rig) if posed else None
    scale = diagonal(surface(rig, pose))
    original = copy.deepcopy((rig.vertices, rig.faces, rig.weights, rig.attributes))
    session = Surgery(rig, pose)
    chain, last, snapshots = [rig], None, []
    for _ in range(data.draw(st.integers(1, 6), label="operations")):
        if len(chain) > 1 and data.draw(st.integers(0, 4)) == 0:
            session.undo()
            chain.pop()
            last = None
        else:
            blades = _stroke_after(last, data.draw, chain[-1], pose)
            opening = data.draw(st.sampled_from([0.0, 0.0, 0.003])) * scale
            try:
                expected = cgaskin.tear(chain[-1], *blades, pose=pose, opening=opening)
            except STROKE_ERRORS as error:
                event(f"a stroke raises {type(error).__name__}")
                before = session.rig
                with pytest.raises(type(error)):
                    session.tear(*blades, opening=opening)
                assert session.rig is before and session.n_operations == len(chain) - 1
                continue
            session.tear(*blades, opening=opening)
            event("a stroke tears")
            chain.append(expected)
            last = blades[1]
        snapshots.append((session.rig, chain[-1]))
        assert_same_mesh(session.rig, chain[-1], scale)
        assert_same_boundary(session, chain[-1])
    for snapshot, expected in snapshots:            # later operations leave earlier snapshots alone
        assert_same_mesh(snapshot, expected, scale)
    for before, after in zip(original, (rig.vertices, rig.faces, rig.weights, rig.attributes)):
        if isinstance(before, dict):
            assert before.keys() == after.keys() and all(np.array_equal(before[k], after[k]) for k in before)
        else:
            np.testing.assert_array_equal(before, after)


def capsule_incision(count, x0=0.1, step=0.014, offset=np.zeros(3)):
    """The issue's incision along the top of the built-in capsule: blades (handle, tip) at x0, x0 +
    step, ... (the plane z = 0.02 runs near rows of vertices)."""
    return [np.array([[x0 + step * i, 0.35, 0.02], [x0 + step * i, 0.0, 0.02]]) + offset for i in range(count)]


def test_a_long_incision_undone_and_redone():
    rig = cgaskin.capsule_arm()
    blades = capsule_incision(31)
    session, chain = Surgery(rig), [rig]
    for i in range(30):
        session.tear(blades[i], blades[i + 1], opening=0.002 * (i % 3 == 0))
        chain.append(cgaskin.tear(chain[-1], blades[i], blades[i + 1], opening=0.002 * (i % 3 == 0)))
    assert_same_mesh(session.rig, chain[-1], 1.0)
    assert_same_boundary(session, chain[-1])
    assert session.n_operations == 30 and len(chain[-1].faces) == session.n_faces
    for _ in range(12):
        session.undo()
    assert_same_mesh(session.rig, chain[18], 1.0)
    assert_same_boundary(session, chain[18])
    for i in range(18, 30):                              # the same strokes again, from the undone state
        session.tear(blades[i], blades[i + 1], opening=0.002 * (i % 3 == 0))
    assert_same_mesh(session.rig, chain[-1], 1.0)
    for _ in range(30):
        session.undo()
    assert_same_mesh(session.rig, rig, 1.0)
    with pytest.raises(InvalidInputError, match="nothing to undo"):
        session.undo()


@pytest.mark.parametrize("where", ["far from the origin", "posed"])
def test_far_from_the_origin_and_posed(where):
    """The capsule moved 1e4 away, and the capsule torn in a pose: the session still follows the
    functional chain."""
    rig, pose, offset = cgaskin.capsule_arm(), None, np.zeros(3)
    if where == "posed":
        pose = rig.pose("wave", 0.4)
    else:
        offset = np.array([1e4, -2e4, 3e4])
        rig = rig.with_mesh(rig.vertices + offset, rig.faces, rig.joints, rig.weights, rig.attributes)
    points = surface(rig, pose)
    start = points[np.argmax(points[:, 1] - np.abs(points[:, 0] - offset[0] - 0.4))]   # on top, near x = 0.4
    blades = [np.array([start + [dx, 0.3, 0.013], start + [dx, -0.1, 0.013]]) for dx in np.linspace(0, 0.3, 8)]
    session, current = Surgery(rig, pose), rig
    for i in range(7):
        session.tear(blades[i], blades[i + 1])
        current = cgaskin.tear(current, blades[i], blades[i + 1], pose=pose)
    assert current.n_faces > rig.n_faces + 7
    assert_same_mesh(session.rig, current, 1.0)


def test_a_session_continues_from_a_saved_file(tmp_path):
    """Save the session's rig, load it, start a new session from the file and go on: the same mesh as
    going on in the first session (the tear labels travel in the file)."""
    rig = cgaskin.capsule_arm()
    blades = capsule_incision(12)
    session = Surgery(rig)
    for i in range(6):
        session.tear(blades[i], blades[i + 1])
    cgaskin.save(session.rig, tmp_path / "torn.glb")
    loaded = cgaskin.load(tmp_path / "torn.glb")
    assert TEAR_LABEL in loaded.attributes
    again = Surgery(loaded)
    for i in range(6, 11):
        session.tear(blades[i], blades[i + 1])
        again.tear(blades[i], blades[i + 1])
    a, b = session.rig, again.rig
    np.testing.assert_array_equal(a.faces, b.faces)
    np.testing.assert_allclose(a.vertices, b.vertices, atol=1e-6)     # (the file stores float32)
    np.testing.assert_array_equal(a.attributes[TEAR_LABEL], b.attributes[TEAR_LABEL])


def test_cut_keeps_both_halves_apart_and_undoes():
    rig = cgaskin.capsule_arm()
    blades = capsule_incision(6)
    session = Surgery(rig)
    session.tear(blades[0], blades[1])
    before = session.rig
    session.cut([1.0, 0.0, 0.0], [1.5, 0.0, 0.0])
    positive, negative = cgaskin.cut(before, [1.0, 0.0, 0.0], [1.5, 0.0, 0.0])
    assert session.n_faces == positive.n_faces + negative.n_faces
    assert session.n_vertices == positive.n_vertices + negative.n_vertices
    assert pieces(session.rig) == pieces(positive) + pieces(negative)      # the halves do not weld
    for i in range(1, 5):                                 # the incision goes on in the negative half
        session.tear(blades[i], blades[i + 1])
    for _ in range(5):                                    # four strokes, then the cut
        session.undo()
    assert_same_mesh(session.rig, before, 1.0)


def test_bad_input_and_failed_strokes_change_nothing():
    rig = cgaskin.capsule_arm()
    session = Surgery(rig)
    blades = capsule_incision(3)
    session.tear(blades[0], blades[1])
    before = session.rig
    with pytest.raises(MissesMeshError, match="scalpel_to"):
        session.tear(blades[1], [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]])
    with pytest.raises(InvalidInputError, match="opening"):
        session.tear(blades[1], blades[2], opening=-1.0)
    with pytest.raises(InvalidInputError, match="scalpel_from"):
        session.tear([[0.0, 0.0, 0.0]], blades[2])
    with pytest.raises(InvalidInputError):
        session.cut([0.0, 0.0, 0.0], [0.5, 0.0, 0.0])                 # a zero normal
    with pytest.raises(InvalidInputError, match="cap"):
        session.cut([1.0, 0.0, 0.0], [0.5, 0.0, 0.0], cap="yes")
    assert session.rig is before and session.n_operations == 1
    with pytest.raises(InvalidInputError, match="Rig"):
        Surgery("not a rig")
    session.tear(blades[1], blades[2])                    # and it goes on
    assert session.n_operations == 2


def test_each_operation_reports_its_cost():
    rig = cgaskin.capsule_arm()
    session = Surgery(rig)
    assert session.last_cost is None
    blades = capsule_incision(3)
    session.tear(blades[0], blades[1])
    cost = session.last_cost
    assert isinstance(cost, cgaskin.OperationCost) and cost.operation == "tear"
    assert 0.0 < cost.seconds < 60.0 and cost.page_faults >= 0
    with pytest.raises(MissesMeshError):                 # a failed stroke is no operation: nothing reported
        session.tear(blades[1], [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]])
    assert session.last_cost is cost
    session.cut([1.0, 0.0, 0.0], [1.5, 0.0, 0.0])
    assert session.last_cost.operation == "cut"
    # the cut makes the session's arrays and tree anew: fresh pages that the process counts (Linux)
    if cgaskin._shared.memory.minor_page_faults() > 0:
        assert session.last_cost.page_faults > 0
    session.undo()
    assert session.last_cost.operation == "undo"


# ---- strokes on a playing model continue one slit (issue 43 item 10) --------------------------------------
def _top(rig):
    """The rows of ``rig``'s vertices on top of the capsule arm (largest z), and the vertices."""
    vertices = np.asarray(rig.vertices)
    return np.flatnonzero(vertices[:, 2] >= vertices[:, 2].max() - 1e-12), vertices


def _blade_over(rig, pose, x):
    """The issue's blade: vertical, 0.3 above and 0.05 below the skin point (lifted by 0.001) posed from
    the rest vertex on top nearest x."""
    rows, vertices = _top(rig)
    row = rows[np.argmin(np.abs(vertices[rows, 0] - x))]
    point = cgaskin.skin(rig, pose)[row] + [0.0, 0.0, 0.001]
    return np.array([point + [0.0, 0.0, 0.3], point - [0.0, 0.0, 0.05]])


_SMALL_ARM = cgaskin.capsule_arm(rings_per_segment=40, segments_around=32)


def _slits(rig) -> int:
    """The boundary loops of the rig's welded mesh: one per separate slit on a closed model."""
    return len(tear_topology(rig).boundary_loops())


@pytest.mark.parametrize("around, opening", [(64, 0.0), (64, 0.01), (512, 0.01)])
def test_strokes_on_a_playing_model_continue_one_slit(around, opening):
    """Issue 43 item 10: 16 strokes on ``capsule_arm(rings_per_segment=410, segments_around=around)``
    playing its clip, stroke k at 0.05 + 0.01k from where the previous stroke's blade was (posed at the
    previous time: the skin has moved since) to a blade over x = 0.2 + 0.005(k + 1): each continues the
    slit from its tip (it started a slit of its own beside it, or fell through the opened gap), and the
    functional chain (``cgaskin.tear_stroke`` on the rig each stroke returns) does the same."""
    rig = cgaskin.capsule_arm(rings_per_segment=410, segments_around=around)
    session, current = Surgery(rig), rig
    scalpel_from = _blade_over(rig, rig.pose(0, 0.05), 0.2)
    for k in range(16):
        pose = rig.pose(0, 0.05 + 0.01 * k)
        scalpel_to = _blade_over(rig, pose, 0.2 + 0.005 * (k + 1))
        stroke = session.tear(scalpel_from, scalpel_to, pose=pose, opening=opening)
        assert k == 0 or stroke.split[0], f"stroke {k} does not continue the slit"
        if around == 64:
            current = cgaskin.tear(current, scalpel_from, scalpel_to, pose=pose, opening=opening)
        scalpel_from = scalpel_to
    assert _slits(session.rig) == 1 and pieces(session.rig) == 1
    if around == 64:
        assert_same_mesh(session.rig, current, 1.0)


@settings(max_examples=15, **SETTINGS)
@given(times=st.lists(st.floats(0.0, 0.2), min_size=6, max_size=6), opening=st.sampled_from([0.0, 0.004]))
def test_continue_slit_follows_the_tip_in_random_poses(times, opening):
    """``Surgery.continue_slit`` in a random pose per stroke: each stroke starts at the tip of the slit
    where that pose carries it (S_i is the tip's skinned position, split: the slit goes on) and the
    strokes make one slit."""
    rig = _SMALL_ARM
    session = Surgery(rig)
    session.tear(_blade_over(rig, rig.rest_pose(), 0.5), _blade_over(rig, rig.rest_pose(), 0.6), opening=opening)
    for k, t in enumerate(times):
        pose = rig.pose("wave", t)
        tip = cgaskin.skin(session.rig, pose)[session.tip]
        stroke = session.continue_slit(_blade_over(rig, pose, 0.7 + 0.1 * k), pose=pose, opening=opening)
        np.testing.assert_allclose(stroke.points[0], tip, rtol=0, atol=1e-9)
        assert stroke.split[0] and stroke.kinds[0] == 0
    assert _slits(session.rig) == 1 and pieces(session.rig) == 1


def test_continue_slit_after_undo_and_its_errors():
    """Undo takes the tip back with the stroke; with no slit to continue -- none yet, the last stroke ended
    on an existing slit (a T junction), a cut since -- continue_slit says so."""
    rig = _SMALL_ARM
    session = Surgery(rig)
    with pytest.raises(InvalidInputError, match="no slit to continue"):
        session.continue_slit(_blade_over(rig, None, 0.6))
    first = session.tear(_blade_over(rig, None, 0.5), _blade_over(rig, None, 0.6))
    second = session.continue_slit(_blade_over(rig, None, 0.7))
    assert second.split[0] and np.array_equal(second.points[0], first.points[-1])
    session.undo()
    again = session.continue_slit(_blade_over(rig, None, 0.8))
    np.testing.assert_array_equal(again.points[0], first.points[-1])
    with pytest.raises(InvalidInputError, match="scalpel_to"):
        session.continue_slit([[0.0, 0.0, 0.0]])
    # a stroke that ends on the slit's side: no tip
    side = session.rig.vertices[again.side_b[1]]
    session.tear([[0.65, -0.15, 1.0], [0.65, -0.15, 0.0]], [[side[0], side[1], 1.0], [side[0], side[1], 0.0]])
    with pytest.raises(InvalidInputError, match="no slit to continue"):
        session.continue_slit(_blade_over(rig, None, 0.9))
    session.undo()
    session.cut([1.0, 0.0, 0.0], [2.5, 0.0, 0.0])
    with pytest.raises(InvalidInputError, match="no slit to continue"):
        session.continue_slit(_blade_over(rig, None, 0.9))
    session.undo()
    assert session.continue_slit(_blade_over(rig, None, 0.9)).split[0]
