"""A session's drill works on the region around the bit (``session_drill.py``): its mesh must be the
functional drill's of the session's mesh (the independent oracle: ``cgaskin.drill`` on ``session.rig``,
which sees the whole mesh), but for the rows inside the bit that the session keeps unused; undo gives
the mesh back bit for bit; bad input and a bit that misses change nothing."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import cgaskin
from cgaskin.surgery.topology import boundary_flags
from tests.surgery.test_drill import through, unit_vectors


def _used(rig) -> tuple:
    """The rig's vertices that faces use (in their order), its faces over them, their joints, weights and
    attributes."""
    used = np.zeros(rig.n_vertices, bool)
    used[rig.faces.ravel()] = True
    renumber = np.cumsum(used) - 1
    attributes = {name: np.asarray(values)[used] for name, values in sorted(rig.attributes.items())}
    return rig.vertices[used], renumber[rig.faces], rig.joints[used], rig.weights[used], attributes


def assert_same_mesh(session_rig, functional):
    got, want = _used(session_rig), _used(functional)
    for name, a, b in zip(("vertices", "faces", "joints", "weights"), got[:4], want[:4]):
        assert a.shape == b.shape and np.array_equal(a, b), name
    assert got[4].keys() == want[4].keys()
    for name in got[4]:
        assert np.array_equal(got[4][name], want[4][name]), name


def _assert_unchanged(session, before):
    np.testing.assert_array_equal(session.rig.faces, before.faces)
    np.testing.assert_array_equal(session.rig.vertices, before.vertices)
    np.testing.assert_array_equal(session.rig.weights, before.weights)


def _drill_both(session, start, end, radius, **options):
    """The session's drill and the functional drill of its mesh before it; where the functional drill
    raises (a bit that misses), the session raises the same error and is unchanged (None)."""
    before = session.rig
    functional = {"pose": session.pose, **options}        # (a session in a pose drills in it)
    try:
        want = cgaskin.drill(before, start, end, radius, **functional)
    except cgaskin.CgaskinError as error:
        with pytest.raises(type(error)):
            session.drill(start, end, radius, **options)
        _assert_unchanged(session, before)
        return None
    result = session.drill(start, end, radius, **options)
    assert_same_mesh(session.rig, want)
    assert isinstance(result, cgaskin.DrillResult) and len(result.replaced) > 0
    return want


@pytest.fixture(scope="module")
def capsule():
    return cgaskin.capsule_arm()


@settings(max_examples=12, deadline=None)
@given(face=st.integers(0, 1375), bary=st.tuples(st.floats(0, 1), st.floats(0, 1)), direction=unit_vectors(),
       before=st.floats(0.0, 0.6), after=st.floats(0.0, 0.6), fraction=st.floats(0.02, 0.3), wall=st.booleans(),
       posed=st.booleans())
def test_session_drills_equal_the_functional_drill(capsule, face, bary, direction, before, after, fraction, wall,
                                                   posed):
    """Bits through a point of the capsule's surface (as ``test_drill``'s random bits), any direction, open or
    walled, at rest or in a pose; the session's boundary flags are the drilled mesh's."""
    assume(before + after > 1e-3)
    pose = capsule.pose(0, 0.6) if posed else None
    points = capsule.vertices if pose is None else cgaskin.skin(capsule, pose)
    u, v = bary if sum(bary) <= 1 else (1 - bary[0], 1 - bary[1])
    a, b, c = points[capsule.faces[face]]
    start, end = through(a + u * (b - a) + v * (c - a), direction, before, after)
    session = cgaskin.Surgery(capsule)
    before_rig = session.rig
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cgaskin.PlacementWarning)
        drilled = _drill_both(session, start, end, fraction * 0.5, pose=pose, wall=wall)
    if drilled is not None:
        rig = session.rig
        used = np.unique(rig.faces)
        flags = boundary_flags(rig.vertices, rig.faces, np.zeros(rig.n_vertices, np.int64))
        assert np.array_equal(session.boundary[used], flags[used])
        session.undo()
    _assert_unchanged(session, before_rig)
    assert session.n_operations == 0


def test_drills_after_tears_in_a_posed_session_and_on_a_coarse_mesh(capsule):
    """A session in a pose, a drill after a slit (tear labels), a second drill through the first hole's
    wall, and a coarse mesh whose faces are larger than the bit (the region grows ring by ring)."""
    pose = capsule.pose(0, 0.5)
    skinned = cgaskin.skin(capsule, pose)
    centre = skinned[np.abs(capsule.vertices[:, 0] - 1.5) < 0.05].mean(axis=0)
    session = cgaskin.Surgery(capsule, pose)
    _drill_both(session, centre - [0, 0, 1.0], centre + [0, 0, 1.0], 0.1)
    session = cgaskin.Surgery(capsule)
    session.tear([[2.0, 0.3, 0.0], [2.0, 0.1, 0.0]], [[2.3, 0.3, 0.0], [2.3, 0.1, 0.0]])
    assert _drill_both(session, [2.15, 0.0, -1.0], [2.15, 0.0, 1.0], 0.08) is not None
    assert _drill_both(session, [2.15, -1.0, 0.0], [2.15, 1.0, 0.0], 0.05, wall=False) is not None
    session.undo()
    session.undo()
    session.undo()
    _assert_unchanged(session, cgaskin.Surgery(capsule).rig)
    coarse = cgaskin.capsule_arm(rings_per_segment=2, segments_around=6)
    for radius in (0.02, 0.1, 0.3):
        assert _drill_both(cgaskin.Surgery(coarse), [1.2, 0.05, -1.0], [1.2, 0.05, 1.0], radius) is not None


def test_a_drill_through_a_seamed_model_from_a_file(models_dir):
    """Fox: attribute seams (copies of one point), UVs and normals; far from its own bounds' centre."""
    rig = cgaskin.load(models_dir / "Fox.glb")
    size = float(np.ptp(rig.vertices, axis=0).max())
    v = rig.vertices[np.argmin(np.linalg.norm(rig.vertices - rig.vertices.mean(axis=0), axis=1))]
    z = np.array([0.0, 0.0, size])
    session = cgaskin.Surgery(rig)
    before = session.rig
    _drill_both(session, v - z, v + z, 0.03 * size)
    _drill_both(session, v - z + [0.05 * size, 0, 0], v + 0.01 * z + [0.05 * size, 0, 0], 0.02 * size)   # blind
    session.undo()
    session.undo()
    _assert_unchanged(session, before)


def test_bad_drills_change_nothing(capsule):
    session = cgaskin.Surgery(capsule)
    before = session.rig
    other = cgaskin.capsule_arm(n_joints=5)
    for args, options in [(([1.0, 0, -1], [1.0, 0, -1], 0.1), {}), (([1.0, 0, -1], [1.0, 0, 1], 0.0), {}),
                          (([1.0, 0, -1], [1.0, 0, 1], float("nan")), {}),
                          (([1.0, 0, -1], [1.0, 0, 1], 0.1), {"wall": "yes"}),
                          (([1.0, 0, -1], [1.0, 0, 1], 0.1), {"pose": other.pose(0, 0.1)})]:
        with pytest.raises(cgaskin.InvalidInputError):
            session.drill(*args, **options)
    with pytest.raises(cgaskin.MissesMeshError):
        session.drill([10.0, 0, -1], [10.0, 0, 1], 0.1)
    _assert_unchanged(session, before)
    assert session.n_operations == 0
