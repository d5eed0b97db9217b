"""The checks of the cut tests (tests/surgery/test_cut*.py): helpers, random rigs, strategies and
``check_cut``, every invariant of a cut that crossed the mesh.

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
from hypothesis import strategies as st

import cgaskin
from cgaskin import Rig, Skeleton, capsule_arm
from cgaskin.surgery.cut import CAP_VERTEX, NEW_VERTEX
from cgaskin.surgery.topology import topology

MODELS = ["Arm5.glb", "3Cylinder4bones.glb", "Fox.glb"]
#: geometric tolerance of the cut checks, in units of the bounding-box diagonal
GEOM = 1e-9
#: relative tolerance of area and volume sums
AREA = 1e-9


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
