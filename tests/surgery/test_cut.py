"""Plane cuts (cgaskin.cut) and the welded topology they run on (cgaskin.topology).

Properties checked on the shared models (Arm5, 3Cylinder4bones, Fox), the procedural capsule arm and
random closed skinned meshes with attribute seams, for random planes (through random points of the
bounding box and through vertices, where vertices lie exactly on the plane), at rest and posed:

* area is preserved (rest cut: rest area; posed cut: area of the skinned halves in that pose);
* every new vertex lies on the plane, on its edge, in the space that was cut; each half on its side;
* original vertices are copied bit for bit (positions, joints, weights, attributes), so skinning a half
  reproduces them exactly in any pose; new vertices get the interpolated top-4 weights;
* no crack along seams: attribute-split copies of a crossed edge get one position, and every boundary
  edge a cut creates lies on the plane; a closed input gives halves bounded by closed loops, and with
  ``cap=True`` watertight, consistently oriented halves whose volumes add up;
* no non-manifold edge is introduced; halves export to glTF and reload;
* a missing plane warns and returns (whole, empty); bad input raises InvalidInputError.
"""
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import cgaskin
from cgaskin.surgery.cut import (CAP_VERTEX, NEW_VERTEX, PlaneMissesMeshWarning, cut, cut_details)
from cgaskin.errors import InvalidInputError
from cgaskin.animation.rig import Rig, Skeleton
from cgaskin.rigs.procedural import capsule_arm
from cgaskin.surgery.topology import clear_topology_cache, rig_topology, topology

MODELS = ["Arm5.glb", "3Cylinder4bones.glb", "Fox.glb"]
#: geometric tolerance of the cut checks, in units of the bounding-box diagonal
GEOM = 1e-9
#: relative tolerance of area and volume sums
AREA = 1e-9

fixture_settings = settings(suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                   HealthCheck.too_slow])


# ---- helpers ------------------------------------------------------------------------------------------
def diagonal(points) -> float:
    return float(np.linalg.norm(np.ptp(points, axis=0))) if len(points) else 0.0


def area(vertices, faces) -> float:
    v = np.asarray(vertices)
    e1, e2 = v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]]
    return 0.5 * float(np.linalg.norm(np.cross(e1, e2), axis=1).sum())


def volume(vertices, faces) -> float:
    v = np.asarray(vertices)
    return float(np.einsum("ij,ij->i", v[faces[:, 0]], np.cross(v[faces[:, 1]], v[faces[:, 2]])).sum() / 6)


def signed_distance(points, result) -> np.ndarray:
    return points @ result.plane[:3] - result.plane[3]


def boundary_is_closed(topo) -> bool:
    """Every welded vertex starts as many boundary edges as it ends (boundary = closed loops)."""
    be = topo.boundary_edges
    inc = topo.edge_face_offsets[be]
    f, k = topo.edge_face_faces[inc], topo.edge_face_corners[inc].astype(np.int64)
    start, end = topo.faces[f, k], topo.faces[f, (k + 1) % 3]
    return np.array_equal(np.bincount(start, minlength=topo.n_welded), np.bincount(end, minlength=topo.n_welded))


def orientation_defects(topo) -> int:
    """Manifold edges whose two faces run along them in the same direction."""
    two = np.flatnonzero(topo.edge_face_counts == 2)
    d = topo.edge_directions()
    o = topo.edge_face_offsets[two]
    return int(np.count_nonzero(d[o] == d[o + 1]))


def interpolated_influences(j_a, w_a, j_b, w_b, t) -> dict:
    """{bone: weight} of (1 - t) row a + t row b over the union of their bones (up to 8)."""
    acc = {}
    for j, w, s in ((j_a, w_a, 1 - t), (j_b, w_b, t)):
        for bone, weight in zip(j, w):
            if weight * s > 0:
                acc[int(bone)] = acc.get(int(bone), 0.0) + weight * s
    return acc


def check_top4(got_joints, got_weights, union):
    """``got`` is the union's 4 largest influences (up to ties), renormalised."""
    got = {int(j): w for j, w in zip(got_joints, got_weights) if w > 0}
    assert set(got) <= set(union) and len(got) == min(4, len(union))
    total = sum(union[b] for b in got)
    for bone, w in got.items():
        assert w == pytest.approx(union[bone] / total, abs=1e-12)
    dropped = [v for b, v in union.items() if b not in got]
    assert max(dropped, default=0.0) <= min(union[b] for b in got) + 1e-12


def chain_skeleton(n_bones, rng) -> Skeleton:
    """A chain of ``n_bones`` nodes with random offsets; rest pose = bind pose."""
    t = rng.normal(size=(n_bones, 3))
    t[0] = 0.0
    local = np.tile(np.eye(4), (n_bones, 1, 1))
    local[:, :3, 3] = t
    glob = np.cumsum(t, axis=0)
    ibm = np.tile(np.eye(4), (n_bones, 1, 1))
    ibm[:, :3, 3] = -glob
    return Skeleton(names=[f"b{i}" for i in range(n_bones)], parents=np.arange(-1, n_bones - 1),
                    rest_translations=t, rest_rotations=np.tile([0.0, 0, 0, 1], (n_bones, 1)),
                    rest_scales=np.ones((n_bones, 3)), rest_matrices=local,
                    bone_nodes=np.arange(n_bones), inverse_bind=ibm)


def random_closed_rig(shape: str, seed: int, split_fraction: float) -> Rig:
    """A closed triangle mesh (trimesh primitive, randomly stretched and moved) with random seams
    (``split_fraction`` of the faces get their own vertex copies, with their own UVs and normals) and
    random 1-4-bone weights on a random chain skeleton."""
    trimesh = pytest.importorskip("trimesh")
    rng = np.random.default_rng(seed)
    mesh = {"sphere": lambda: trimesh.creation.icosphere(subdivisions=2),
            "torus": lambda: trimesh.creation.torus(1.0, 0.35, major_sections=24, minor_sections=12),
            "box": lambda: trimesh.creation.box(),
            "capsule": lambda: trimesh.creation.capsule(height=2.0, radius=0.5, count=[12, 12])}[shape]()
    vertices = np.asarray(mesh.vertices) * rng.uniform(0.5, 2.0, 3) + rng.normal(size=3)
    faces = np.asarray(mesh.faces, np.int64).copy()
    n = len(vertices)
    n_bones = int(rng.integers(1, 7))
    # smooth weights (Gaussian falloff from random bone centres, top 4 kept), so that a pose bends the
    # surface smoothly instead of crumpling it (a section of a self-intersecting surface has no cap)
    centres = vertices[rng.integers(0, n, n_bones)]
    falloff = np.exp(-np.sum((vertices[:, None] - centres[None]) ** 2, axis=2) / rng.uniform(0.3, 2.0))
    falloff = np.concatenate([falloff, np.zeros((n, 4))], axis=1)      # at least 4 columns
    order = np.argsort(-falloff, axis=1, kind="stable")[:, :4]
    weights = np.take_along_axis(falloff, order, axis=1) + 1e-9
    weights[:, min(n_bones, 4):] = 0.0
    weights /= weights.sum(axis=1, keepdims=True)
    joints = np.where(weights > 0, order, 0)
    # seams: chosen faces take private copies of their corners (same position and skin, as in files;
    # their own NORMAL and TEXCOORD_0 below)
    chosen = np.flatnonzero(rng.random(len(faces)) < split_fraction)
    if len(chosen):
        corners = faces[chosen].reshape(-1)
        faces[chosen] = (n + np.arange(len(corners))).reshape(-1, 3)
        vertices, joints, weights = (np.concatenate([a, a[corners]]) for a in (vertices, joints, weights))
    n = len(vertices)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights,
               skeleton=chain_skeleton(n_bones, rng), attributes={"NORMAL": normals, "TEXCOORD_0": rng.random((n, 2))},
               name=f"random_{shape}")


def random_pose(rig, rng, max_angle=0.6):
    pose = rig.rest_pose()
    for node in range(rig.skeleton.n_nodes):
        axis = rng.normal(size=3)
        pose = pose.rotate(node, axis / np.linalg.norm(axis), rng.uniform(-max_angle, max_angle))
    return pose


# ---- the checks shared by every property test ---------------------------------------------------------
def check_cut(rig, result, pose=None, closed=False, capped=False):
    """Every invariant of a cut that crossed the mesh (see the module docstring)."""
    halves = (result.positive, result.negative)
    affected = pose is not None
    rest_skin = cgaskin.skin(rig, pose) if affected else np.asarray(rig.vertices, float)
    diag = diagonal(rest_skin)
    n_bones = rig.skeleton.n_bones
    input_topo = topology(rig.vertices, rig.faces)
    skinned = [cgaskin.skin(h, pose) if affected else h.vertices for h in halves]

    # area preserved (in the space that was cut); caps excluded
    total = 0.0
    for h, pos, src in zip(halves, skinned, result.sources):
        body = h.faces[~np.all(src[h.faces] == CAP_VERTEX, axis=1)]
        total += area(pos, body)
    assert abs(total - area(rest_skin, rig.faces)) <= AREA * area(rest_skin, rig.faces)

    for side, (h, pos, src) in enumerate(zip(halves, skinned, result.sources)):
        d = signed_distance(pos, result)
        sign = 1.0 if side == 0 else -1.0
        assert (sign * d >= -GEOM * diag).all(), "a vertex lies on the wrong side"
        old = src >= 0
        new = src == NEW_VERTEX
        # original vertices are copies, bit for bit
        assert np.array_equal(h.vertices[old], rig.vertices[src[old]])
        assert np.array_equal(h.weights[old], rig.weights[src[old]])
        assert np.array_equal(h.joints[old], rig.joints[src[old]])
        for key, values in rig.attributes.items():
            assert np.array_equal(h.attributes[key][old], np.asarray(values)[src[old]]), key
        # hence skinning reproduces them exactly (at rest or in the pose)
        assert np.array_equal(pos[old], rest_skin[src[old]])
        # new vertices: on the plane, on their edge (in the space that was cut), in edge order
        first = result.first_new[side]
        assert np.all(src[first:first + len(result.edge_t)] == NEW_VERTEX)
        assert np.count_nonzero(new) == len(result.edge_t)
        a, b = result.edge_vertices[:, 0], result.edge_vertices[:, 1]
        t = result.edge_t
        assert ((t > 0) & (t < 1)).all()
        on_edge = rest_skin[a] * (1 - t)[:, None] + rest_skin[b] * t[:, None]
        assert np.abs(pos[new] - on_edge).max(initial=0) <= GEOM * diag
        assert np.abs(d[new]).max(initial=0) <= GEOM * diag
        for key, values in rig.attributes.items():
            values = np.asarray(values, float)
            expected = values[a] * (1 - t)[:, None] + values[b] * t[:, None]
            if key == "NORMAL":
                norm = np.linalg.norm(expected, axis=1, keepdims=True)
                expected = np.divide(expected, norm, out=expected.copy(), where=norm > 0)
            assert np.allclose(h.attributes[key][new], expected, rtol=0, atol=1e-12), key
        # weights: valid everywhere, the interpolated top 4 on new vertices
        w, j = h.weights, h.joints
        assert np.isfinite(w).all() and (w >= 0).all()
        assert (np.count_nonzero(w, axis=1) <= 4).all()
        assert np.abs(w.sum(axis=1) - 1).max() <= 1e-6
        assert np.abs(w[new].sum(axis=1) - 1).max(initial=0) <= 1e-12
        assert ((j >= 0) & (j < n_bones)).all()
        for row, e in zip(np.flatnonzero(new)[:50], range(50)):
            union = interpolated_influences(rig.joints[a[e]], rig.weights[a[e]], rig.joints[b[e]],
                                            rig.weights[b[e]], t[e])
            check_top4(j[row], w[row], union)

        # topology: no non-manifold edge introduced; seams do not crack
        topo = topology(h.vertices, h.faces)
        assert len(topo.nonmanifold_edges) <= len(input_topo.nonmanifold_edges)
        if capped and closed:
            assert (topo.edge_face_counts == 2).all(), "a capped half of a closed mesh is not watertight"
        elif closed:
            assert boundary_is_closed(topo)
            # every boundary edge the cut made lies on the plane (an off-plane one would be a crack)
            ends = pos[topo.representative[topo.edges[topo.boundary_edges]]]
            assert np.abs(signed_distance(ends.reshape(-1, 3), result)).max(initial=0) <= GEOM * diag
        else:
            assert len(topo.boundary_edges) >= 0
        if orientation_defects(input_topo) == 0:
            assert orientation_defects(topo) == 0

    # copies of one welded edge get one position: the positions of new vertices depend only on the
    # welded edge
    w = input_topo.welded
    key = np.sort(np.stack([w[result.edge_vertices[:, 0]], w[result.edge_vertices[:, 1]]], axis=1), axis=1)
    _, first_of, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    assert np.array_equal(result.new_positions, result.new_positions[first_of][inverse.reshape(-1)])


def crossing(rig, normal, point, pose=None):
    """Whether the plane has vertices strictly on both sides (else the cut may miss)."""
    pos = cgaskin.skin(rig, pose) if pose is not None else rig.vertices
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    d = (pos - point) @ n
    tol = 1e-8 * diagonal(pos)
    return (d > tol).any() and (d < -tol).any()


# ---- fixtures and strategies --------------------------------------------------------------------------
_RIGS = {}


def model(models_dir, name) -> Rig:
    if name not in _RIGS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")         # assimp files' weight sums (see rigs/gltf.py)
            _RIGS[name] = capsule_arm() if name == "capsule" else cgaskin.load(models_dir / name)
    return _RIGS[name]


unit = st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 3).filter(lambda v: np.linalg.norm(v) > 0.05)
axis_normals = st.sampled_from([(1.0, 0, 0), (0, 1.0, 0), (0, 0, 1.0), (-1.0, 0, 0), (0, 0, -1.0)])
normals = st.one_of(unit, axis_normals)


@st.composite
def plane_points(draw, vertices):
    """A point in the bounding box, or exactly a vertex (so that vertices lie on the plane)."""
    if draw(st.booleans()):
        return np.asarray(vertices[draw(st.integers(0, len(vertices) - 1))], float)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    u = np.array(draw(st.tuples(*[st.floats(0.05, 0.95)] * 3)))
    return lo + u * (hi - lo)


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


# ---- specific cases -----------------------------------------------------------------------------------
def test_plane_through_a_ring_of_vertices_makes_no_new_vertex():
    rig = capsule_arm()
    ring_x = 0.25                                  # a ring of the cylinder (x = k * 3 / 36)
    assert np.count_nonzero(rig.vertices[:, 0] == ring_x) == 16
    result = cut_details(rig, [1, 0, 0], [ring_x, 0, 0], cap=True)
    assert len(result.edge_t) == 0
    a, b = result.positive, result.negative
    ring = np.flatnonzero(rig.vertices[:, 0] == ring_x)
    for h, src in zip((a, b), result.sources):
        assert set(ring) <= set(src[src >= 0].tolist())        # on-plane vertices in both halves
        assert len(np.unique(src[src >= 0])) == np.count_nonzero(src >= 0)  # no duplicates
    assert len(a.faces) + len(b.faces) - 2 * 14 == len(rig.faces)  # 16-gon caps: 14 triangles each
    check_cut(rig, result, closed=True, capped=True)


def test_seam_copies_of_a_crossed_edge_share_one_position():
    # every face of the capsule gets private vertices (like Fox): all edges are seams
    base = capsule_arm()
    f = base.faces
    flat = f.reshape(-1)
    rig = Rig(vertices=base.vertices[flat], faces=np.arange(len(flat)).reshape(-1, 3), joints=base.joints[flat],
              weights=base.weights[flat], skeleton=base.skeleton, clips=base.clips,
              attributes={"NORMAL": base.attributes["NORMAL"][flat],
                          "TEXCOORD_0": np.random.default_rng(0).random((len(flat), 2))})
    result = cut_details(rig, [1, 0.2, 0.1], [1.3, 0.01, 0.02], cap=True)
    # two faces on each crossed edge: two new vertices per welded edge, at one position
    assert len(result.edge_t) == 2 * len(np.unique(result.new_positions, axis=0))
    check_cut(rig, result, closed=True, capped=True)


def test_plane_touching_one_vertex_misses():
    rig = capsule_arm()
    pole = rig.vertices[:, 0].argmin()
    with pytest.warns(PlaneMissesMeshWarning):
        a, b = cut(rig, [1, 0, 0], rig.vertices[pole])
    assert len(b.faces) == 0 and np.array_equal(a.faces, rig.faces)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_missing_plane_returns_whole_and_empty(sign):
    rig = capsule_arm()
    with pytest.warns(PlaneMissesMeshWarning, match="does not cross"):
        a, b = cut(rig, [sign, 0, 0], [-10.0, 0, 0])
    whole, empty = (a, b) if sign > 0 else (b, a)
    assert np.array_equal(whole.vertices, rig.vertices) and whole.vertices is not rig.vertices
    assert np.array_equal(whole.faces, rig.faces) and np.array_equal(whole.weights, rig.weights)
    assert whole.attributes["NORMAL"] is not rig.attributes["NORMAL"]
    assert empty.vertices.shape == (0, 3) and empty.faces.shape == (0, 3)
    assert empty.joints.shape == (0, 4) and empty.weights.shape == (0, 4)
    assert empty.attributes["NORMAL"].shape == (0, 3)
    assert whole.skeleton is rig.skeleton and empty.skeleton is rig.skeleton
    assert [c.name for c in empty.clips] == ["wave"]


def test_face_in_the_plane_goes_to_the_side_it_bounds():
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box()                   # the unit cube around the origin
    rig = Rig(vertices=np.asarray(box.vertices), faces=np.asarray(box.faces, np.int64),
              joints=np.zeros((8, 4), np.int64), weights=np.tile([1.0, 0, 0, 0], (8, 1)),
              skeleton=chain_skeleton(1, np.random.default_rng(0)))
    # the plane of the top face: the whole cube is below it (on the negative side)
    with pytest.warns(PlaneMissesMeshWarning):
        a, b = cut(rig, [0, 0, 1], [0, 0, 0.5])
    assert len(a.faces) == 0 and len(b.faces) == 12


def test_caller_rig_is_not_modified():
    rig = capsule_arm()
    for arr in (rig.vertices, rig.faces, rig.joints, rig.weights, rig.attributes["NORMAL"]):
        arr.flags.writeable = False                # any write would raise
    before = {k: np.array(v) for k, v in (("v", rig.vertices), ("f", rig.faces), ("w", rig.weights))}
    pose = rig.pose("wave", 0.8)
    a, b = cut(rig, [1, 1, 0], [1.5, 0, 0], pose=pose, cap=True)
    assert np.array_equal(rig.vertices, before["v"]) and np.array_equal(rig.faces, before["f"])
    assert np.array_equal(rig.weights, before["w"])
    assert a.vertices.flags.writeable and not np.shares_memory(a.vertices, rig.vertices)


def test_posed_cut_places_new_vertices_on_the_posed_plane():
    rig = capsule_arm()
    pose = rig.pose("wave", 1.0)                   # elbow bent 90 degrees
    posed = cgaskin.skin(rig, pose)
    normal, point = np.array([1.0, 1.0, 0.0]), posed.mean(axis=0)
    result = cut_details(rig, normal, point, pose=pose)
    for h, first in zip((result.positive, result.negative), result.first_new):
        new = cgaskin.skin(h, pose)[first:]
        assert np.abs((new - point) @ normal / np.linalg.norm(normal)).max() <= 1e-12 * diagonal(posed)
    # the rest positions are not the rest-space edge points: the cut happened in the pose
    lerp = (rig.vertices[result.edge_vertices[:, 0]] * (1 - result.edge_t)[:, None]
            + rig.vertices[result.edge_vertices[:, 1]] * result.edge_t[:, None])
    first = result.first_new[0]
    assert np.abs(result.positive.vertices[first:] - lerp).max() > 1e-6


def test_cap_normals_face_outwards():
    rig = capsule_arm()
    for pose in (None, rig.pose("wave", 0.6)):
        result = cut_details(rig, [1, 0.1, 0], [1.4, 0, 0], pose=pose, cap=True)
        for h, src, sign in zip((result.positive, result.negative), result.sources, (-1, 1)):
            caps = src == CAP_VERTEX
            assert caps.any()
            normals = cgaskin.skin_normals(h, pose)[caps] if pose is not None else h.attributes["NORMAL"][caps]
            assert np.allclose(normals, sign * result.plane[:3], atol=1e-9)


def test_nested_loops_are_capped_by_even_odd():
    """Two concentric spheres (a hollow ball, inner one inward) and a third inside: the cap of a cut
    through the centre is an annulus plus a disc."""
    trimesh = pytest.importorskip("trimesh")
    parts = []
    for radius, flip in ((3.0, False), (2.0, True), (1.0, False)):
        s = trimesh.creation.icosphere(subdivisions=3, radius=radius)
        faces = np.asarray(s.faces)[:, ::-1] if flip else np.asarray(s.faces)
        parts.append((np.asarray(s.vertices), faces))
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.concatenate([v for v, _ in parts])
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)])
    n = len(vertices)
    rig = Rig(vertices=vertices, faces=faces.astype(np.int64), joints=np.zeros((n, 4), np.int64),
              weights=np.tile([1.0, 0, 0, 0], (n, 1)), skeleton=chain_skeleton(1, np.random.default_rng(1)))
    result = cut_details(rig, [0.1, 0.2, 1.0], [0.01, 0.02, 0.03], cap=True)
    check_cut(rig, result, closed=True, capped=True)
    total = volume(result.positive.vertices, result.positive.faces) + volume(result.negative.vertices,
                                                                              result.negative.faces)
    assert total == pytest.approx(volume(vertices, faces), rel=1e-12)
    assert volume(vertices, faces) > 0


def test_open_boundary_in_the_plane_is_not_capped(models_dir):
    rig = model(models_dir, "Arm5.glb")          # 37 boundary edges (welded) before any cut
    before = len(rig_topology(rig).boundary_edges)
    result = cut_details(rig, [1, 0.3, 0.2], rig.vertices.mean(axis=0), cap=True)
    after = sum(len(topology(h.vertices, h.faces).boundary_edges) for h in (result.positive, result.negative))
    assert after == before


@pytest.mark.parametrize("name", MODELS + ["capsule"])
def test_halves_export_and_reload(models_dir, tmp_path, name):
    export = pytest.importorskip("cgaskin.rigs.export")
    rig = model(models_dir, name)
    a, b = cut(rig, [1, 0.2, 0.1], rig.vertices.mean(axis=0), cap=True)
    for h, label in ((a, "a"), (b, "b")):
        path = export.save_gltf(h, tmp_path / f"{label}.glb")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            back = cgaskin.load(path)
        assert np.array_equal(back.faces, h.faces)
        assert np.allclose(back.vertices, h.vertices, rtol=1e-6, atol=1e-6 * diagonal(h.vertices))
        assert np.allclose(back.weights, h.weights, atol=1e-6)
        assert back.skeleton.n_bones == rig.skeleton.n_bones and len(back.clips) == len(rig.clips)


# ---- bad input ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("normal,point", [
    ([0, 0, 0], [0, 0, 0]), ([np.nan, 0, 1], [0, 0, 0]), ([1, 0, 0], [0, np.inf, 0]), ([1, 0], [0, 0, 0]),
    ([1, 0, 0], [[0, 0, 0]]), ("up", [0, 0, 0]), ([1, 0, 0], None)])
def test_bad_planes(normal, point):
    with pytest.raises(InvalidInputError):
        cut(capsule_arm(), normal, point)


def test_bad_rigs_and_poses(models_dir):
    rig = capsule_arm()
    with pytest.raises(InvalidInputError, match="another skeleton"):
        cut(rig, [1, 0, 0], [1, 0, 0], pose=model(models_dir, "Fox.glb").rest_pose())
    with pytest.raises(InvalidInputError):
        cut(rig, [1, 0, 0], [1, 0, 0], pose="wave")
    with pytest.raises(InvalidInputError):
        cut(rig.vertices, [1, 0, 0], [1, 0, 0])
    with pytest.raises(InvalidInputError):
        cut(rig, [1, 0, 0], [1, 0, 0], cap="yes")
    with pytest.raises(InvalidInputError, match="no faces"):
        cut(rig.with_mesh(rig.vertices, np.empty((0, 3), np.int64), rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    nan = rig.vertices.copy()
    nan[3, 1] = np.nan
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(nan, rig.faces, rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    out_of_range = rig.faces.copy()
    out_of_range[0, 0] = len(rig.vertices)
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, out_of_range, rig.joints, rig.weights), [1, 0, 0], [1, 0, 0])
    bad_joints = rig.joints.copy()
    bad_joints[0, 0] = 99
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, rig.faces, bad_joints, rig.weights), [1, 0, 0], [1, 0, 0])
    with pytest.raises(InvalidInputError):
        cut(rig.with_mesh(rig.vertices, rig.faces, rig.joints, rig.weights[:, :3]), [1, 0, 0], [1, 0, 0])


# ---- topology -----------------------------------------------------------------------------------------
def test_topology_welds_attribute_seams(models_dir):
    fox = model(models_dir, "Fox.glb")
    topo = topology(fox.vertices, fox.faces)
    assert len(np.unique(fox.faces)) == 3 * len(fox.faces)          # fully unindexed
    assert topo.n_welded == len(np.unique(fox.vertices, axis=0))
    assert (topo.edge_face_counts == 2).all()                       # closed once welded
    assert orientation_defects(topo) == 0
    assert np.array_equal(fox.vertices[topo.representative[topo.welded]], fox.vertices)
    arm = model(models_dir, "Arm5.glb")
    topo = topology(arm.vertices, arm.faces)
    assert len(topo.boundary_edges) == 37
    assert len(topo.vertex_edges) > len(topo.edges)                 # seams: more vertex edges


def test_topology_structure():
    rig = capsule_arm()
    topo = topology(rig.vertices, rig.faces)
    m = len(rig.faces)
    assert topo.n_edges == 3 * m // 2 and (topo.edge_face_counts == 2).all()
    # incidence lists agree with face_edges
    for e in range(0, topo.n_edges, 97):
        faces = topo.edge_faces(e)
        for f in faces:
            assert e in topo.face_edges[f]
    # edges are the welded corner pairs
    f, k = topo.edge_face_faces, topo.edge_face_corners.astype(np.int64)
    pairs = np.sort(np.stack([topo.faces[f, k], topo.faces[f, (k + 1) % 3]], axis=1), axis=1)
    assert np.array_equal(pairs, topo.edges[np.repeat(np.arange(topo.n_edges), topo.edge_face_counts)])
    assert np.array_equal(topo.find_edges(topo.edges[:, 1], topo.edges[:, 0]), np.arange(topo.n_edges))
    assert topo.find_edges([0], [len(rig.vertices) - 1])[0] == -1
    # -0.0 and 0.0 weld
    v = np.array([[0.0, 0, 0], [-0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    t = topology(v, np.array([[0, 2, 4], [1, 4, 3]]))
    assert t.welded[0] == t.welded[1] and t.n_welded == 4 and t.n_edges == 5
    assert len(t.boundary_edges) == 4 and len(t.vertex_edges) == 6
    assert t.boundary_loops() == [[0, 1, 3, 2]]          # welded ids of vertices 0, 2, 4, 3


def test_topology_boundary_loops(models_dir):
    plane = model(models_dir, "PlaneWith3Bones.glb")
    loops = topology(plane.vertices, plane.faces).boundary_loops()
    assert [len(loop) for loop in loops] == [16]


def test_rig_topology_is_cached():
    rig = capsule_arm()
    first = rig_topology(rig)
    assert rig_topology(rig) is first
    clear_topology_cache()
    assert rig_topology(rig) is not first


def test_topology_rejects_bad_arrays():
    with pytest.raises(InvalidInputError):
        topology(np.zeros((3, 2)), np.zeros((1, 3), np.int64))
    with pytest.raises(InvalidInputError):
        topology(np.zeros((3, 3)), np.array([[0, 1, 3]]))
    with pytest.raises(InvalidInputError):
        topology(np.full((3, 3), np.nan), np.array([[0, 1, 2]]))


def test_other_dtypes_are_accepted():
    base = capsule_arm()
    rig = Rig(vertices=base.vertices.astype(np.float32), faces=base.faces.astype(np.int32),
              joints=base.joints.astype(np.uint8), weights=base.weights.astype(np.float32),
              skeleton=base.skeleton, attributes={"NORMAL": base.attributes["NORMAL"].astype(np.float32),
                                                  "_ID": np.arange(len(base.vertices))})
    result = cut_details(rig, [1, 0.2, 0], [1.2, 0, 0], cap=True)
    a = result.positive
    assert a.vertices.dtype == np.float64 and a.joints.dtype == np.int64 and a.weights.dtype == np.float64
    assert a.attributes["NORMAL"].dtype == np.float32 and a.attributes["_ID"].shape == (len(a.vertices),)
    old = result.sources[0] >= 0
    assert np.array_equal(a.attributes["_ID"][old], result.sources[0][old])


def test_placement_in_rest_space():
    from cgaskin.surgery.new_vertices import _place_in_rest
    rng = np.random.default_rng(3)
    affines = rng.normal(size=(3, 12))
    joints = np.array([[0, 1, 2, 0], [0, 0, 0, 0]])
    weights = np.array([[0.5, 0.3, 0.2, 0.0], [1.0, 0, 0, 0]])
    x = rng.normal(size=(2, 3))
    blend = np.einsum("vk,vkc->vc", weights, affines[joints]).reshape(-1, 3, 4)
    target = np.einsum("vij,vj->vi", blend[:, :, :3], x) + blend[:, :, 3]
    rest, residual, singular = _place_in_rest(target, x + 0.1, joints, weights, affines)
    assert np.allclose(rest, x, atol=1e-12) and residual.max() < 1e-13 and not singular.any()
    # a singular blend (here all zero) keeps the guess and says so
    rest, residual, singular = _place_in_rest(target, x, joints, weights, np.zeros((3, 12)))
    assert singular.all() and np.array_equal(rest, x)


@pytest.mark.parametrize("up", [1.0, -1.0])
def test_face_in_the_plane_is_kept_by_the_side_below_its_normal(up):
    # face 0 lies in z = 0 with normal +z; face 1 rises to z = 1 from its edge
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]])
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    rig = Rig(vertices=vertices, faces=faces, joints=np.zeros((4, 4), np.int64),
              weights=np.tile([1.0, 0, 0, 0], (4, 1)), skeleton=chain_skeleton(1, np.random.default_rng(0)))
    above, below = cut(rig, [0, 0, up], [0, 0, 0])
    if up < 0:
        above, below = below, above
    assert np.array_equal(below.faces, [[0, 1, 2]]) and np.array_equal(below.vertices, vertices[:3])
    assert len(above.faces) == 1 and np.array_equal(above.vertices, vertices[1:])
