"""The drill at its edges (issue 43 B): radii from far below the model's rounding to beyond its size,
closed shells of either winding (several, disjoint, nested or overlapping), a bit that takes the whole
mesh. Every check is plain numpy on the output: closedness on welded positions (every edge of exactly two
faces), the consistency of the winding (each directed edge once), the count of new vertices against the
drill's own stated cap and its prediction."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, given, settings, strategies as st

import cgaskin
from cgaskin.errors import InvalidInputError, MissesMeshError
from cgaskin.surgery.drill import api as drill_api

from tests.helpers.drill_cases import CASES as WALL_CASES       # (test_drill_wall's holes)
from tests.helpers.cut_checks import chain_skeleton, random_closed_rig, random_pose
from tests.helpers.tear_checks import get_rig
from tests.surgery.test_drill import diagonal, drilled_positions, through, unit_vectors

#: a few drills per property (no shrinking: a failing drill prints its example at once)
few = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow],
               phases=[Phase.explicit, Phase.reuse, Phase.generate])



@pytest.fixture(scope="module")
def capsule():
    return cgaskin.capsule_arm()


# ---- plain numpy oracles --------------------------------------------------------------------------------
def welded_faces(rig) -> np.ndarray:
    """The faces (m, 3) over welded positions (vertices at bitwise-equal positions are one)."""
    ids = np.unique(np.asarray(rig.vertices), axis=0, return_inverse=True)[1].reshape(-1)
    return ids[np.asarray(rig.faces)]


def edge_counts(rig) -> np.ndarray:
    """How many faces each (welded, undirected) edge has."""
    faces = welded_faces(rig)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


def unclosed(rig) -> int:
    """The edges not shared by exactly two faces (0: closed and manifold)."""
    return int(np.count_nonzero(edge_counts(rig) != 2))


def consistently_wound(rig) -> bool:
    """Whether each directed (welded) edge is used once: neighbours wound alike."""
    faces = welded_faces(rig)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return len(np.unique(directed, axis=0)) == len(directed)


def signed_volume(rig) -> float:
    p = np.asarray(rig.vertices, float)[np.asarray(rig.faces)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def flipped(rig):
    """``rig`` with every face wound the other way (inward: negative signed volume)."""
    return rig.with_mesh(rig.vertices, np.asarray(rig.faces)[:, ::-1], rig.joints, rig.weights,
                         dict(rig.attributes))


def new_vertices(result) -> int:
    return result.rig.n_vertices - result.first_new


def drilled(rig, *bit, **options):
    """(DrillResult, the warnings it gave)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = cgaskin.drill_details(rig, *bit, **options)
    return result, [w for w in caught if issubclass(w.category, cgaskin.OpenRimWarning)]


# ---- 6: small radii, the cap on new vertices, the prediction --------------------------------------------
@few
@given(exponent=st.floats(-12.0, math.log10(3.57)), x=st.floats(0.2, 3.0), y=st.floats(-0.2, 0.2),
       wall=st.booleans(), blind=st.booleans())
def test_any_radius_drills_within_the_cap_or_is_refused(capsule, exponent, x, y, wall, blind):
    """Radii log-uniform from 1e-12 to the capsule's size, through it or blind: each drill either makes
    at most the stated cap of new vertices (and no more than predicted), closed where walled, or raises
    InvalidInputError (a radius below the smallest, a bit that takes the whole mesh); never
    MemoryError, InternalError or a crash."""
    radius = 10.0 ** exponent
    start, end = [x, y, -1.0], [x, y, 0.0 if blind else 1.0]
    try:
        result, caught = drilled(capsule, start, end, radius, wall=wall)
    except InvalidInputError:
        return
    except MissesMeshError:                      # (a blind bit that ends before the surface)
        assume(False)
    count = new_vertices(result)
    assert count <= drill_api.MAX_NEW_VERTICES
    assert count <= drill_api.predicted_new_vertices(capsule, start, end, radius, wall=wall)
    if wall:
        assert unclosed(result.rig) == 0 and not caught


def test_a_radius_below_the_smallest_is_refused_naming_it(capsule):
    """The smallest radius is a stated multiple of the rounding of the model's coordinates (float32's,
    as a file holds them, at the model's size); below it InvalidInputError names it; at twice it the
    hole is made, walled and closed, in a few hundred new vertices."""
    smallest = drill_api.smallest_radius(capsule)
    size = diagonal(np.asarray(capsule.vertices))
    assert smallest == pytest.approx(drill_api.SMALLEST_RADIUS_ROUNDINGS * np.finfo(np.float32).eps * size)
    bit = ([1.0, 0.0, -1.0], [1.0, 0.0, 1.0])
    for radius in (1e-300, 1e-12, 1e-9, 0.5 * smallest):
        for wall in (True, False):
            with pytest.raises(InvalidInputError, match=f"{smallest:.3g}"):
                cgaskin.drill(capsule, *bit, radius, wall=wall)
            with pytest.raises(InvalidInputError, match=f"{smallest:.3g}"):
                drill_api.predicted_new_vertices(capsule, *bit, radius, wall=wall)
    result, caught = drilled(capsule, *bit, 2.0 * smallest)
    assert unclosed(result.rig) == 0 and not caught and result.wall_faces > 0
    assert new_vertices(result) <= 5000


def test_a_small_hole_in_the_fox_follows_the_mesh(models_dir):
    """Fox (diagonal 176), radius 0.01 through the body: the wall's rings follow the mesh's edges along
    the axis (not the radius: 1.03M new vertices before), and the hole is closed where the body is."""
    fox = get_rig("Fox.glb", models_dir)
    points = np.asarray(fox.vertices)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    start, end = centre - [100.0, 0.0, 0.0], centre + [100.0, 0.0, 0.0]
    result, _ = drilled(fox, start, end, 0.01)
    assert 0 < new_vertices(result) <= 20_000
    assert new_vertices(result) <= drill_api.predicted_new_vertices(fox, start, end, 0.01)


def test_a_drill_over_the_cap_is_refused_before_it_runs(capsule, monkeypatch):
    """With the cap lowered below a hole's predicted count, the functional and the session's drill raise
    InvalidInputError naming the prediction and the cap, and the session is unchanged."""
    bit = ([1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 0.1)
    predicted = drill_api.predicted_new_vertices(capsule, *bit)
    assert predicted >= new_vertices(cgaskin.drill_details(capsule, *bit))
    monkeypatch.setattr(drill_api, "MAX_NEW_VERTICES", predicted - 1)
    with pytest.raises(InvalidInputError, match=f"{predicted}.*{predicted - 1}"):
        cgaskin.drill(capsule, *bit)
    session = cgaskin.Surgery(capsule)
    with pytest.raises(InvalidInputError, match=f"{predicted - 1}"):
        session.drill(*bit)
    assert session.n_operations == 0 and session.rig.n_faces == capsule.n_faces


def test_a_sessions_prediction_is_the_functional_one(capsule):
    """``session_drill.predicted_session_drill`` (from the session's BVH, no copy of its mesh) predicts
    what ``predicted_new_vertices`` does for the session's mesh, at rest and in a pose; the session's
    drill makes no more."""
    from cgaskin.surgery.session_drill import predicted_session_drill
    session = cgaskin.Surgery(capsule)
    pose = capsule.pose("wave", 0.4)
    rest = np.asarray(capsule.vertices)
    centre = cgaskin.skin(capsule, pose)[np.abs(rest[:, 0] - 1.5) < 0.1].mean(axis=0)    # (in the arm, posed)
    for bit, options in ((([1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 0.1), {}),
                         (([2.0, 0.0, -1.0], [2.0, 0.0, 0.0], 0.05), {"wall": False}),
                         ((centre - [0.0, 0.0, 1.0], centre + [0.0, 0.0, 1.0], 0.08), {"pose": pose})):
        predicted = predicted_session_drill(session, *bit, **options)
        assert predicted == drill_api.predicted_new_vertices(session.rig, *bit, **options) > 0
        before = session.n_vertices
        session.drill(*bit, **options)
        assert session.n_vertices - before <= predicted
    with pytest.raises(InvalidInputError, match="smallest"):
        predicted_session_drill(session, [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 1e-9)


@few
@given(shape=st.sampled_from(["sphere", "torus", "box", "capsule"]), seed=st.integers(0, 2 ** 32 - 1),
       posed=st.booleans(), wall=st.booleans(), data=st.data())
def test_the_prediction_bounds_random_drills(shape, seed, posed, wall, data):
    """On random closed meshes (seams, posed or not), random bits of radii from a thousandth to half of
    the mesh's size: the new vertices never exceed ``predicted_new_vertices``, nor the cap."""
    rig = random_closed_rig(shape, seed, 0.3)
    pose = random_pose(rig, np.random.default_rng(seed + 1), max_angle=0.3) if posed else None
    points = drilled_positions(rig, pose)
    diag = diagonal(points)
    point = points[data.draw(st.integers(0, rig.n_vertices - 1))]
    radius = 10.0 ** data.draw(st.floats(-3.0, math.log10(0.5))) * diag
    start, end = through(point, data.draw(unit_vectors()), 0.3 * diag, data.draw(st.floats(0.0, 0.3)) * diag)
    try:
        result = cgaskin.drill_details(rig, start, end, radius, pose=pose, wall=wall)
    except MissesMeshError:
        assume(False)
    except InvalidInputError as error:           # (a bit that takes the whole mesh)
        assert "whole mesh" in str(error)
        return
    predicted = drill_api.predicted_new_vertices(rig, start, end, radius, pose=pose, wall=wall)
    assert new_vertices(result) <= predicted <= drill_api.MAX_NEW_VERTICES


# ---- 7: closed shells of either winding -------------------------------------------------------------------
@pytest.mark.parametrize("case", list(WALL_CASES))
def test_an_inward_wound_tube_is_walled_and_closed(capsule, case):
    """The capsule with its faces wound inward (negative signed volume, as some exporters write it) gets
    walls as the outward one does, for every hole of test_drill_wall.py (through, blind, along the axis,
    grazing, oblique, from the pole, lengthwise): closed, manifold, consistently wound (the fills too),
    no warning; the same from a start inside the capsule (the wall runs down to the back's pole)."""
    inward = flipped(capsule)
    assert signed_volume(inward) < 0.0
    bit = WALL_CASES[case]
    outward_result, _ = drilled(capsule, *bit)
    result, caught = drilled(inward, *bit)
    assert result.wall_faces > 0 and abs(result.wall_faces - outward_result.wall_faces) <= 0.05 * result.wall_faces
    assert unclosed(result.rig) == 0 and consistently_wound(result.rig) and not caught
    assert signed_volume(result.rig) < 0.0
    for rig in (capsule, inward):
        from_inside, caught = drilled(rig, [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], 0.1)
        assert from_inside.wall_faces > 0 and unclosed(from_inside.rig) == 0 and not caught
        assert consistently_wound(from_inside.rig)


def test_a_surface_wound_against_its_neighbours(capsule):
    """Half of the capsule wound inward, half outward (closed, its winding inconsistent): a hole through
    both halves is walled and closed; a blind hole whose bottom lies where the winding number is 0 is
    left open, with an ``OpenRimWarning`` counting the edges left (the edges an oracle finds open)."""
    vertices, faces = np.asarray(capsule.vertices), np.asarray(capsule.faces).copy()
    upper = vertices[faces].mean(axis=1)[:, 2] > 0.0
    faces[upper] = faces[upper][:, ::-1]
    mixed = capsule.with_mesh(vertices, faces, capsule.joints, capsule.weights, dict(capsule.attributes))
    result, caught = drilled(mixed, [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 0.1)
    assert result.wall_faces > 0 and unclosed(result.rig) == 0 and not caught
    blind, caught = drilled(mixed, [1.0, 0.0, -1.0], [1.0, 0.0, 0.05], 0.1)
    left = unclosed(blind.rig)
    assert left > 0 and blind.unclosed_edges == left
    assert len(caught) == 1 and f"{left} edge" in str(caught[0].message)


def _shell(kind: str, size: float, centre, inward: bool):
    """(vertices, faces) of a closed trimesh shell around ``centre`` of about ``size`` radius."""
    import trimesh
    mesh = (trimesh.creation.icosphere(subdivisions=2, radius=size) if kind == "sphere" else
            trimesh.creation.capsule(height=size, radius=0.5 * size, count=[12, 12]))
    vertices = np.asarray(mesh.vertices, float) + centre
    faces = np.asarray(mesh.faces, np.int64)
    return vertices, faces[:, ::-1] if inward else faces


def _shells_rig(shells):
    """A rig of several closed shells (one bone)."""
    vertices, faces, offset = [], [], 0
    for v, f in shells:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    vertices = np.concatenate(vertices)
    n = len(vertices)
    joints, weights = np.zeros((n, 4), np.int64), np.zeros((n, 4))
    weights[:, 0] = 1.0
    return cgaskin.Rig(vertices=vertices, faces=np.concatenate(faces), joints=joints, weights=weights,
                       skeleton=chain_skeleton(1, np.random.default_rng(0)), name="shells")


@few
@given(kinds=st.lists(st.sampled_from(["sphere", "capsule"]), min_size=1, max_size=3),
       inward=st.lists(st.booleans(), min_size=3, max_size=3), layout=st.sampled_from(["apart", "nested", "overlap"]),
       offset=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)), radius=st.floats(0.05, 0.3),
       start=st.floats(-2.0, 0.5), end=st.floats(0.5, 8.0))
def test_walled_holes_in_shells_of_either_winding(kinds, inward, layout, offset, radius, start, end):
    """Closed shells (icospheres and capsules) wound either way, apart along the x axis, nested one in
    another, or overlapping, drilled along the axis or grazing them (from outside or from inside a
    shell, through or blind): disjoint shells (apart or nested) stay closed and manifold, consistently
    wound; whatever the shells, a walled drill whose result is not closed says so (``OpenRimWarning``,
    counting the edges left)."""
    shells = []
    for i, kind in enumerate(kinds):
        if layout == "apart":
            centre, size = [3.0 * i, 0.0, 0.0], 1.0
        elif layout == "nested":
            centre, size = [0.2 * i, 0.0, 0.0], 1.0 * 0.45 ** i
        else:
            centre, size = [1.1 * i, 0.1 * i, 0.0], 1.0
        shells.append(_shell(kind, size, np.array(centre), inward[i]))
    rig = _shells_rig(shells)
    smallest = 1.0 * 0.45 ** (len(kinds) - 1) if layout == "nested" else 1.0
    bit = ([start * 3.0 - 1.5, *(smallest * np.asarray(offset))], [end, *(smallest * np.asarray(offset))],
           radius * smallest)
    try:
        result, caught = drilled(rig, *bit)
    except MissesMeshError:
        assume(False)
    except InvalidInputError as error:
        assert "whole mesh" in str(error)
        return
    left = unclosed(result.rig)
    if layout != "overlap":
        assert left == 0, f"{left} edges not shared by two faces"
        assert not caught
        if max(abs(o) for o in offset) + radius < 0.5:     # (a grazing fill may fold: its winding aside)
            assert consistently_wound(result.rig)
    if left:
        assert result.unclosed_edges == left and len(caught) == 1 and f"{left} edge" in str(caught[0].message)


# ---- 8: a bit bigger than the model ---------------------------------------------------------------------
def test_a_bit_that_takes_the_whole_mesh_is_refused(capsule):
    """A bit that takes away every face raises InvalidInputError saying so (not an empty rig), walled or
    not, at rest or in a pose, functional or in a session (unchanged). (A bit that takes one part of
    several is still a drill: test_drill_wall.py.)"""
    everything = ([-1.0, 0.0, 0.0], [4.0, 0.0, 0.0], 1.0)
    for wall in (True, False):
        with pytest.raises(InvalidInputError, match="whole mesh"):
            cgaskin.drill(capsule, *everything, wall=wall)
    with pytest.raises(InvalidInputError, match="whole mesh"):
        cgaskin.drill_details(capsule, [-5.0, 0.0, 0.0], [8.0, 0.0, 0.0], 6.0, pose=capsule.pose("wave", 0.3))
    session = cgaskin.Surgery(capsule)
    with pytest.raises(InvalidInputError, match="whole mesh"):
        session.drill(*everything)
    assert session.n_operations == 0 and session.rig.n_faces == capsule.n_faces


# ---- 17: one way to chain a boundary into loops ---------------------------------------------------------
def test_the_rims_are_chained_by_topologys_directed_loops(capsule, monkeypatch):
    """The walls chain the rims' edges into loops with topology's walk (``chained_edges``: the default
    choice of ``directed_loops``, the one way to chain directed edges into loops), not a copy of it;
    the loops a drill finds are ``directed_loops``' of its rims' edges."""
    from cgaskin.surgery import loops
    from cgaskin.surgery.drill import rim, wall
    assert not hasattr(rim, "rim_loops") and rim.chained_edges is loops.chained_edges
    found = {}
    walls = wall._rim_loops

    def spy(patch, rim_rows, frame):
        tails, heads, a, b, edges, offsets = rim.rim_loop_edges(patch.faces, patch.row_point, rim_rows, patch.n_points)
        found["loops"] = [a[edges[i:j]].tolist() for i, j in zip(offsets[:-1], offsets[1:])]
        found["directed"] = loops.directed_loops(a, b)
        return walls(patch, rim_rows, frame)
    monkeypatch.setattr(wall, "_rim_loops", spy)
    result = cgaskin.drill_details(capsule, [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], 0.1)
    assert found["loops"] == found["directed"] and len(found["loops"]) == 2
    assert result.wall_faces > 0 and unclosed(result.rig) == 0


def _directed_loops_before(start, end, choose=None) -> list:
    """``loops.directed_loops`` as it was in Python before it walked in compiled code (the oracle)."""
    outgoing: dict = {}
    for i, s in enumerate(start.tolist()):
        outgoing.setdefault(s, []).append(i)
    used, loops = [False] * len(start), []
    end_list, start_list = end.tolist(), start.tolist()
    for first in range(len(start)):
        if used[first]:
            continue
        loop, i = [], first
        while True:
            used[i] = True
            loop.append(start_list[i])
            vertex = end_list[i]
            candidates = [j for j in outgoing.get(vertex, ()) if not used[j] or j == first]
            if not candidates:
                break
            if len(candidates) == 1:
                pick = candidates[0]
            elif choose is None:
                pick = first if first in candidates else candidates[0]
            else:
                pick = candidates[choose(start_list[i], vertex, candidates)]
            if pick == first:
                loops.append(loop)
                break
            i = pick
    return loops


@settings(max_examples=300, deadline=None)
@given(edges=st.lists(st.tuples(st.integers(0, 7), st.integers(0, 7)), max_size=30), salt=st.integers(0, 5),
       with_choose=st.booleans())
def test_directed_loops_chain_as_before(edges, salt, with_choose):
    """``directed_loops`` (now one compiled walk, which the drill's rims use too) gives the loops the
    Python version gave, for any directed edges (touching loops, chains, repeated edges, self-loops),
    with the default choice and with a caller's ``choose``, asked the same questions in the same order."""
    from cgaskin.surgery.loops import directed_loops
    start = np.array([a for a, _ in edges], np.int64)
    end = np.array([b for _, b in edges], np.int64)
    asked = {True: [], False: []}

    def chooser(now):
        def choose(previous, vertex, candidates):
            asked[now].append((previous, vertex, list(candidates)))
            return (previous * 7 + vertex * 3 + salt) % len(candidates)
        return choose if with_choose else None
    assert directed_loops(start, end, chooser(True)) == _directed_loops_before(start, end, chooser(False))
    assert asked[True] == asked[False]
