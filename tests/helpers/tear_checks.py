"""The checks of the tear tests (tests/surgery/test_tear*.py): rigs, poses, random strokes, and the
independent checks of a stroke's result.

Invariants of a stroke (``check_stroke``):
* every path vertex lies on the tear plane (1e-9 of the bounding-box diagonal; a vertex of the mesh
  within the snap distance, ``tol.snap``: the plane goes through it), in the space torn (rest, or
  skinned in the pose);
* the welded boundary that the tear adds is exactly the path, once per side;
* with opening 0 the area is unchanged (relative 1e-9) and the original vertices keep their rows;
* weights are finite, >= 0, at most 4 per vertex, summing to 1; no non-manifold edge appears;
* the torn rig skins, animates, dilates and exports like the original.
When the tear reports that the plane's section does not lead from S_i to S_{i+1}, an independent
check (connected pieces of the section within the swept region and short of the far side beyond the
blade's tip, by brute force over all faces) must agree.
"""
from __future__ import annotations

import warnings

import numpy as np
from hypothesis import assume, strategies as st

import cgaskin
from cgaskin import TearPathError, TriangleBVH, capsule_arm, skin, tear_stroke
from cgaskin.surgery.tear import SNAP_TOLERANCE, tear_topology

from .swept_region import hull_distance

PLANE_TOL = 1e-9        # path vertices on the tear plane, relative to the diagonal
AREA_TOL = 1e-9         # relative area change with opening 0
MODELS = ["Arm5.glb", "3Cylinder4bones.glb", "Fox.glb", "capsule"]

try:
    from cgaskin.rigs.export import save_gltf
except ImportError:                                  # pragma: no cover - export is optional here
    save_gltf = None


# ---- rigs and poses ------------------------------------------------------------------------------------
_RIGS: dict = {}


def get_rig(name, models_dir=None):
    if name not in _RIGS:
        if name == "capsule":
            _RIGS[name] = capsule_arm()
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")             # weight renormalisation notices
                _RIGS[name] = cgaskin.load(models_dir / name)
    return _RIGS[name]


def some_pose(name, rig):
    """A pose that bends the mesh: a clip frame when the rig has clips, else a joint rotation."""
    if rig.clips:
        return rig.pose(0, 0.7 * rig.clips[0].duration)
    joint = {"Arm5.glb": "Character1_RightForeArm", "3Cylinder4bones.glb": "joint2"}[name]
    return rig.rest_pose().rotate(joint, [0.3, 0.2, 1.0], 0.6)


def surface(rig, pose):
    return np.asarray(rig.vertices, float) if pose is None else skin(rig, pose)


def diagonal(points):
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def areas(points, faces):
    return np.linalg.norm(np.cross(points[faces[:, 1]] - points[faces[:, 0]],
                                   points[faces[:, 2]] - points[faces[:, 0]]), axis=1) / 2


# ---- strokes -------------------------------------------------------------------------------------------
def unit(v):
    return v / np.linalg.norm(v)


def face_normal(points, face):
    a, b, c = points[face]
    return unit(np.cross(b - a, c - a))


@st.composite
def strokes(draw, rig, points, radius=0.03):
    """Two blades through two nearby surface points (within ``radius`` of the diagonal), each
    crossing the surface near its normal, handle outside."""
    faces = np.asarray(rig.faces)
    diag = diagonal(points)
    f0 = draw(st.integers(0, len(faces) - 1))
    w0 = np.array(draw(st.tuples(*[st.floats(0.01, 1.0)] * 3)))
    p0 = (w0 / w0.sum()) @ points[faces[f0]]
    centroids = points[faces].mean(axis=1)
    near = np.union1d(np.flatnonzero(np.linalg.norm(centroids - p0, axis=1) < radius * diag), [f0])
    f1 = int(near[draw(st.integers(0, len(near) - 1))])
    w1 = np.array(draw(st.tuples(*[st.floats(0.01, 1.0)] * 3)))
    p1 = (w1 / w1.sum()) @ points[faces[f1]]
    assume(np.linalg.norm(p1 - p0) > 1e-3 * diag)         # a stroke that moves
    blades = []
    for p, f in ((p0, f0), (p1, f1)):
        n = face_normal(points, faces[f])
        tilt = np.array(draw(st.tuples(*[st.floats(-0.6, 0.6)] * 3)))
        d = unit(n + tilt) if (n + tilt) @ n > 0.3 else n
        h = draw(st.floats(0.005, 0.05)) * diag
        blades.append(np.array([p + h * d, p - h * d]))
    return blades[0], blades[1]


# ---- independent checks --------------------------------------------------------------------------------
def pieces(rig) -> int:
    """Connected pieces of the welded mesh (faces joined by welded edges)."""
    topo = tear_topology(rig)
    welded = topo.welded[np.asarray(rig.faces)]
    parent = np.arange(welded.max() + 1)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    for a, b in np.concatenate([welded[:, [0, 1]], welded[:, [1, 2]]]):
        parent[find(a)] = find(b)
    return len({find(v) for v in np.unique(welded)})


def welded_edges(topo, vertex_pairs):
    w = topo.welded
    return {tuple(sorted((int(w[a]), int(w[b])))) for a, b in vertex_pairs}


def boundary_edges(topo):
    return {tuple(map(int, e)) for e in topo.edges[topo.boundary_edges]}


def check_weights(rig, first_new):
    """Finite, >= 0, at most 4 per vertex; the rows the tear made sum to 1 (1e-12), the others as
    the loader left them (``cgaskin.tolerances.tol.weight_sum``)."""
    w = np.asarray(rig.weights)
    assert np.isfinite(w).all() and (w >= 0).all()
    assert (np.count_nonzero(w, axis=1) <= 4).all()
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=0, atol=1e-6)
    np.testing.assert_allclose(w[first_new:].sum(axis=1), 1.0, rtol=0, atol=1e-12)


def check_stroke(rig, result, pose, opening=0.0):
    """The invariants listed in the module docstring, for one stroke."""
    torn = result.rig
    n = rig.n_vertices
    before, after = surface(rig, pose), surface(torn, pose)
    diag = diagonal(before)
    plane = result.plane
    path = np.concatenate([result.side_a, result.side_b])
    k = len(result.points)

    # path vertices on the plane (a vertex of the mesh within the snap distance: the plane goes through
    # it); the original vertices untouched (opening 0)
    kinds = np.concatenate([result.kinds, result.kinds])
    scale = np.where(kinds == 0, max(SNAP_TOLERANCE, PLANE_TOL) / PLANE_TOL, 1.0)    # (distances in PLANE_TOL)
    distance = (after[path] @ plane[:3] - plane[3]) / scale
    if opening == 0:
        assert np.abs(distance).max() <= PLANE_TOL * diag
        np.testing.assert_allclose(after[result.side_a], result.points, rtol=0, atol=PLANE_TOL * diag)
        np.testing.assert_array_equal(torn.vertices[:n], rig.vertices)
        area0, area1 = areas(before, np.asarray(rig.faces)).sum(), areas(after, torn.faces).sum()
        assert abs(area1 / area0 - 1) <= AREA_TOL
    else:
        # the split points moved apart by `opening` along the normal, the ends stayed
        gap = (after[result.side_a] - after[result.side_b]) @ plane[:3]
        np.testing.assert_allclose(gap[result.split], opening, rtol=1e-9, atol=1e-9 * diag)
        assert np.abs(distance[np.concatenate([~result.split, ~result.split])]).max() <= PLANE_TOL * diag
    check_weights(torn, n)
    for name, values in rig.attributes.items():
        assert len(torn.attributes[name]) == torn.n_vertices
    if "NORMAL" in torn.attributes:
        np.testing.assert_allclose(np.linalg.norm(torn.attributes["NORMAL"][n:], axis=1), 1.0, atol=1e-9)

    # topology: the new welded boundary is the path, once per side; nothing non-manifold
    t0, t1 = tear_topology(rig), tear_topology(torn)
    assert len(t1.nonmanifold_edges) == len(t0.nonmanifold_edges) == 0
    # (a segment that jumps across an existing slit is no edge: each of its ends splits a boundary edge)
    cut = ~result.jumps[1:]
    side_a = welded_edges(t1, zip(result.side_a[:-1][cut], result.side_a[1:][cut]))
    side_b = welded_edges(t1, zip(result.side_b[:-1][cut], result.side_b[1:][cut]))
    assert len(side_a) == len(side_b) == cut.sum() and not side_a & side_b
    new_boundary = boundary_edges(t1)
    assert side_a | side_b <= new_boundary
    jump_ends = np.flatnonzero(result.jumps[1:])
    split_old = sum(result.kinds[j] == 1 for j in np.concatenate([jump_ends, jump_ends + 1]))
    assert len(new_boundary) == len(t0.boundary_edges) + 2 * cut.sum() + split_old
    if opening == 0 and not result.jumps.any():
        # the other boundary edges are the old ones (same end positions; an old edge at a split end of
        # the path now ends at one of the end's copies)
        def ends(topo, points, edges):
            rep = topo.representative
            return {frozenset((points[rep[a]].tobytes(), points[rep[b]].tobytes())) for a, b in edges}
        old = ends(t0, np.asarray(rig.vertices), t0.edges[t0.boundary_edges])
        rest = ends(t1, np.asarray(torn.vertices), [e for e in new_boundary - (side_a | side_b)])
        assert rest == old
    assert result.split[1:-1].all()


def check_like_original(rig, torn, pose, tmp_path=None):
    """The torn rig skins, animates and dilates like the original (the original vertices land where
    they did), and exports."""
    n = rig.n_vertices
    dilated = pose.dilate(pose.skeleton.names[-1], 1.3)
    for p in (pose, dilated) + ((rig.pose(0, 0.3 * rig.clips[0].duration),) if rig.clips else ()):
        np.testing.assert_array_equal(skin(torn, p)[:n], skin(rig, p))
        assert np.isfinite(skin(torn, p)).all()
    if tmp_path is not None and save_gltf is not None:
        path = save_gltf(torn, tmp_path / "torn.glb")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            back = cgaskin.load(path)
        np.testing.assert_array_equal(back.faces, torn.faces)
        np.testing.assert_allclose(back.vertices, torn.vertices, rtol=1e-6,
                                   atol=1e-6 * diagonal(torn.vertices))
        np.testing.assert_allclose(back.weights, torn.weights, atol=1e-6)


def _beyond_the_tips(rig, topo, points, d, plane, blades, diag) -> np.ndarray:
    """(m,) bool: the faces whose piece of the plane's section crosses the line of a blade beyond its tip
    (blades that lie in the plane), in the plane: where the blade never reached (the far side of a limb)."""
    n = plane[:3]
    faces = topo.welded[np.asarray(rig.faces)]
    cut = np.zeros(len(faces), bool)
    for handle, tip in np.asarray(blades, np.float64):
        if max(abs(handle @ n - plane[3]), abs(tip @ n - plane[3])) > SNAP_TOLERANCE * diag:
            continue
        u = unit(tip - handle)
        v = np.cross(n, u)
        ends = []                               # the two points where the section crosses each face
        for k in range(3):
            a, b = faces[:, k], faces[:, (k + 1) % 3]
            t = d[a] / np.where(d[a] == d[b], 1.0, d[a] - d[b])
            ends.append(((np.sign(d[a]) * np.sign(d[b]) < 0), points[a] + t[:, None] * (points[b] - points[a])))
        crossed = np.stack([e[0] for e in ends], axis=1)                   # (m, 3)
        both = crossed.sum(axis=1) == 2
        first = np.argmax(crossed, axis=1)
        second = 2 - np.argmax(crossed[:, ::-1], axis=1)
        p = np.stack([e[1] for e in ends], axis=1)[np.arange(len(faces)), first]
        q = np.stack([e[1] for e in ends], axis=1)[np.arange(len(faces)), second]
        pu, pv, qu, qv = (p - tip) @ u, (p - tip) @ v, (q - tip) @ u, (q - tip) @ v
        across = both & ((pv < 0) != (qv < 0))
        at = pu + (qu - pu) * pv / np.where(pv == qv, 1.0, pv - qv)
        cut |= across & (at > SNAP_TOLERANCE * diag)
    return cut


def section_separates(rig, result_plane, hits, pose, within=None):
    """Brute force: do the two hit faces lie on different connected pieces of the plane's section?
    (faces crossed by the plane, joined across crossed edges with two faces, where the crossing lies
    within ``within`` = (blades, margin) of the blades' hull when given, through faces whose piece of the
    section does not cross the line of a blade beyond its tip: the far side, which the blade never
    reached). None when a vertex lies on the plane (the simple sign test does not decide then)."""
    topo = tear_topology(rig)
    points = surface(rig, pose)[topo.representative]
    d = points @ result_plane[:3] - result_plane[3]
    if np.any(np.abs(d) <= SNAP_TOLERANCE * diagonal(points)):
        return None
    sign = np.sign(d)
    parent = np.arange(rig.n_faces)
    beyond = (np.zeros(rig.n_faces, bool) if within is None else
              _beyond_the_tips(rig, topo, points, d, result_plane, within[0], diagonal(points)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    crossed = np.flatnonzero(sign[topo.edges[:, 0]] * sign[topo.edges[:, 1]] < 0)
    for e in crossed:
        faces = topo.edge_faces(e)
        if within is not None:
            a, b = points[topo.edges[e]]
            da, db = d[topo.edges[e]]
            if hull_distance(a + da / (da - db) * (b - a), within[0]) > within[1]:
                continue
        if len(faces) == 2 and not beyond[faces].any():
            parent[find(faces[0])] = find(faces[1])
    bvh = TriangleBVH(surface(rig, pose), rig.faces)
    f0, _ = bvh.first_hit(*hits[0])
    f1, _ = bvh.first_hit(*hits[1])
    return find(f0) != find(f1)


# ---- fixed strokes --------------------------------------------------------------------------------------
def capsule_blades(x0, x1, z0=0.05, z1=0.1):
    """Vertical blades (handle above, +y) over the capsule arm at x0 and x1."""
    return (np.array([[x0, 1.0, z0], [x0, -1.0, z0]]), np.array([[x1, 1.0, z1], [x1, -1.0, z1]]))


def some_tear(rig, pose=None, seed=0):
    """A deterministic stroke between two nearby face centres (blades along the normals) whose path
    exists, and its result."""
    rng = np.random.default_rng(seed)
    points, faces = surface(rig, pose), np.asarray(rig.faces)
    centres, diag = points[faces].mean(axis=1), diagonal(points)
    for _ in range(100):
        f0 = int(rng.integers(len(faces)))
        dist = np.linalg.norm(centres - centres[f0], axis=1)
        f1 = int(rng.choice(np.flatnonzero((dist > 0.01 * diag) & (dist < 0.05 * diag))))
        blades = [np.array([centres[f] + 0.02 * diag * face_normal(points, faces[f]),
                            centres[f] - 0.02 * diag * face_normal(points, faces[f])]) for f in (f0, f1)]
        try:
            return tear_stroke(rig, *blades, pose=pose)
        except TearPathError:
            continue
    raise AssertionError("no stroke found")
