"""The BVH an editing session keeps across strokes (cgaskin.surgery.dynamic_bvh.DynamicBVH): after
random removals, insertions and moves, every query agrees with brute force over the live triangles
(the same watertight test, in a plain loop) and with a TriangleBVH built afresh; ties, automatic
rebuilds, checks, and the caller's arrays. Its speed: ``python -m benchmarks.bench_dynamic_bvh``.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import cgaskin.surgery.dynamic_bvh as dyn
from cgaskin import TriangleBVH, capsule_arm
from cgaskin._shared.jit import kernel
from cgaskin.errors import InvalidInputError
from cgaskin.surgery.bvh import _first_hit as static_first_hit, _shear, _watertight
from cgaskin.surgery.dynamic_bvh import DynamicBVH, dyn_faces_near_plane, dyn_first_hit
from cgaskin.surgery.dynamic_bvh_edits import SAH


@kernel()
def _brute_hits(positions, faces, ids, a, b):
    """(t, face) of every crossing of a -> b with the faces ``ids``, by the BVH's watertight test."""
    kx, ky, kz, sx, sy, sz = _shear(b - a)
    out = []
    for i in range(ids.shape[0]):
        t = _watertight(positions, faces, ids[i], a, kx, ky, kz, sx, sy, sz)
        if t >= 0.0 and t <= 1.0:
            out.append((t, ids[i]))
    return out


@kernel()
def _compiled_queries(arrays, a, b, lo, hi, normal, offset, delta):
    """The module's compiled queries, called from another kernel."""
    face, t = dyn_first_hit(arrays, a, b)
    return face, t, dyn_faces_near_plane(arrays, lo, hi, normal, offset, delta)


class Model:
    """The mesh as the test keeps it (the oracle's state): positions (n, 3) and faces (F, 3) rows by
    face id, which grow by reallocation (as a session's buffers do) or change in place, and the live
    face ids. The BVH reads these very arrays."""

    def __init__(self, points, faces):
        self.positions = np.array(points, np.float64)
        self.faces = np.array(faces, np.int64)
        self.live = set(range(len(faces)))
        self.next_id = len(faces)

    def tri(self, f):
        return self.positions[self.faces[f]]

    def arrays(self):
        """(ids (k,), corners (k, 9)) of the live faces, by id."""
        ids = np.array(sorted(self.live), np.int64)
        return ids, self.positions[self.faces[ids]].reshape(-1, 9)

    def add_vertices(self, points):
        """Append positions (p, 3) (a new array); returns their ids."""
        n = len(self.positions)
        self.positions = np.concatenate((self.positions, points))
        return np.arange(n, n + len(points))

    def set_face(self, f, corners):
        """Face f := corners (3,) vertex ids, the faces array reallocated when f is past its end."""
        if f >= len(self.faces):
            grown = np.zeros((max(f + 1, 2 * len(self.faces)), 3), np.int64)
            grown[:len(self.faces)] = self.faces
            self.faces = grown
        self.faces[f] = corners
        self.live.add(f)

    def pieces(self, f, m, count, step=None):
        """Take live face f out, put ``count`` pieces of it in (its edges j -> j+1 fanned to a new vertex
        at m): their new ids (``step`` draws the gap to the next id; 1 if None)."""
        corners, mv = self.faces[f].copy(), self.add_vertices(m[None])[0]
        self.live.discard(f)
        ids = []
        for j in range(count):
            ids.append(self.next_id)
            self.set_face(self.next_id, [corners[j], corners[(j + 1) % 3], mv])
            self.next_id += 1 if step is None else step()
        return ids


def random_edits(bvh, model, rng, steps, scale):
    """Strokes: remove a few faces near a random one, insert 1-3 pieces of each (inside it), move a
    few faces by up to ``scale``: either their own new corners, or their vertices in place (every
    live face on them moves too, and is updated)."""
    for _ in range(steps):
        ids, tri = model.arrays()
        if len(ids) < 8:
            break
        centre = tri[rng.integers(len(ids))].reshape(3, 3).mean(axis=0)
        near = ids[np.argsort(np.abs(tri.reshape(-1, 3, 3).mean(axis=1) - centre).sum(axis=1))]
        removed = near[:rng.integers(1, 6)]
        # half the strokes insert each piece into the leaf of its face (a session's ``near``), before
        # that face goes; the others remove first and let the pieces descend from the root
        beside = rng.integers(2) == 0
        if not beside:
            bvh.remove(removed)
        new_ids, parents = [], []
        for f in removed:
            m = rng.dirichlet(np.ones(3)) @ model.tri(f)   # inside: the fan of pieces covers the face
            pieces = model.pieces(f, m, rng.integers(1, 4), lambda: rng.integers(1, 50))  # sparse ids
            new_ids += pieces
            parents += [f] * len(pieces)
        if beside:
            bvh.insert(np.array(new_ids), model.positions, model.faces, near=np.array(parents))
            bvh.remove(removed)
        else:
            bvh.insert(np.array(new_ids), model.positions, model.faces)
        moved = near[len(removed):len(removed) + rng.integers(0, 5)]
        if not len(moved):
            continue
        if rng.integers(2) == 0:
            for f in moved:
                model.faces[f] = model.add_vertices(model.tri(f) + rng.normal(0, scale, (3, 3)))
            bvh.update(moved, model.positions, model.faces)
        else:
            vertices = np.unique(model.faces[moved])
            model.positions[vertices] += rng.normal(0, scale, (len(vertices), 3))    # the BVH's array
            live = np.array(sorted(model.live))
            bvh.update(live[np.isin(model.faces[live], vertices).any(axis=1)], model.positions, model.faces)


def check_sah_sum(bvh):
    """The SAH sum the edits keep (``sums[SAH]``, what the rebuild test reads) equals the sum over the tree
    as it is: inner nodes weigh 1, leaves their live count, each times its box's area."""
    st = bvh._st
    total, stack = 0.0, [0]
    while stack:
        node = stack.pop()
        d = st.hi[node] - st.lo[node]
        area = 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]) if d[0] >= 0.0 else 0.0
        if st.left[node] >= 0:
            total += area
            stack += [int(st.left[node]), int(st.right[node])]
        else:
            total += st.count[node] * area
    assert st.sums[SAH] == pytest.approx(total, rel=1e-9, abs=1e-12)


def check_queries(bvh, model, rng, n_segments=20):
    """Every query against brute force over the model's live triangles and against a fresh TriangleBVH."""
    ids, tri = model.arrays()
    assert bvh.n_faces == len(ids)
    check_sah_sum(bvh)
    fresh = TriangleBVH(tri.reshape(-1, 3), np.arange(3 * len(ids)).reshape(-1, 3))
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    for _ in range(n_segments):
        a, b = rng.uniform(lo - 0.1, hi + 0.1), rng.uniform(lo - 0.1, hi + 0.1)
        expected = sorted(_brute_hits(model.positions, model.faces, ids, a, b))
        face, t = bvh.first_hit(a, b)
        fresh_face, fresh_t = fresh.first_hit(a, b)
        if not expected:
            assert face == -1 and np.isnan(t) and fresh_face == -1
        else:
            assert (t, face) == expected[0]
            assert fresh_t == t and ids[fresh_face] in [f for s, f in expected if s == t]
        faces, ts = bvh.all_hits(a, b)
        assert list(zip(ts.tolist(), faces.tolist())) == [(t, int(f)) for t, f in expected]
    tlo, thi = tri.reshape(-1, 3, 3).min(axis=1), tri.reshape(-1, 3, 3).max(axis=1)
    for _ in range(5):
        box_lo = rng.uniform(lo, hi)
        box_hi = box_lo + rng.uniform(0, 0.5, 3) * (hi - lo)
        meets = np.all((tlo <= box_hi) & (thi >= box_lo), axis=1)
        assert np.array_equal(bvh.faces_in_box(box_lo, box_hi), ids[meets])
        normal, offset, delta = rng.normal(size=3), rng.normal(), rng.uniform(0, 0.05)
        x = tri.reshape(-1, 3, 3)
        s = ((-offset + normal[0] * x[..., 0]) + normal[1] * x[..., 1]) + normal[2] * x[..., 2]
        near = meets & (s.min(axis=1) <= delta) & (s.max(axis=1) >= -delta)
        assert np.array_equal(bvh.faces_near_plane(box_lo, box_hi, normal, offset, delta), ids[near])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), steps=st.integers(1, 30), scale=st.sampled_from([0.0, 1e-3, 0.05]))
def test_edits_on_the_capsule_match_brute_force(seed, steps, scale):
    rig = capsule_arm()
    rng = np.random.default_rng(seed)
    model = Model(rig.vertices, rig.faces)
    bvh = DynamicBVH(model.positions, model.faces)
    random_edits(bvh, model, rng, steps, scale)
    check_queries(bvh, model, rng)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), m=st.integers(1, 40), steps=st.integers(0, 25),
       capacity=st.sampled_from([0, 3, None]))
def test_edits_on_random_soups_match_brute_force(seed, m, steps, capacity):
    """Small random triangle soups, no spare room at first (the arrays must grow)."""
    rng = np.random.default_rng(seed)
    model = Model(rng.uniform(-1, 1, (3 * m, 3)), rng.permutation(3 * m).reshape(m, 3))
    bvh = DynamicBVH(model.positions, model.faces, capacity=capacity)
    random_edits(bvh, model, rng, steps, 0.3)
    if model.live:
        check_queries(bvh, model, rng)


def test_equal_t_picks_the_lowest_face_id():
    """Coincident triangles wherever they sit in the tree: the lowest live id wins."""
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    f = 100
    copies = np.zeros((30_000, 3), np.int64)       # rows by face id: copies of face f at the ids used
    copies[:len(faces)] = faces
    copies[len(faces):] = faces[f]
    bvh = DynamicBVH(points, faces)
    c = points[faces[f]]
    inside, normal = c.mean(axis=0), np.cross(c[1] - c[0], c[2] - c[0])
    a, b = inside - normal / np.linalg.norm(normal) * 1e-3, inside + normal / np.linalg.norm(normal) * 1e-3
    bvh.insert([10 ** 4, 10 ** 4 + 7], points, copies)
    assert bvh.first_hit(a, b)[0] == f and bvh.first_hit(b, a)[0] == f
    bvh.remove([f])
    assert bvh.first_hit(a, b)[0] == 10 ** 4
    bvh.insert([3 * 10 ** 4 - 1], points, copies)         # more copies fill the leaf and split it
    bvh.insert(np.empty(0, np.int64), points, copies)
    for k in range(12):
        bvh.insert([2 * 10 ** 4 + k], points, copies)
    assert bvh.first_hit(a, b)[0] == 10 ** 4
    bvh.remove([10 ** 4])
    assert bvh.first_hit(a, b)[0] == 10 ** 4 + 7
    two = DynamicBVH(np.vstack([c, c]), [[3, 4, 5], [0, 1, 2]])
    assert two.first_hit(a, b)[0] == 0
    faces_hit, ts = two.all_hits(a, b)
    assert faces_hit.tolist() == [0, 1] and ts[0] == ts[1]


def test_degradation_triggers_a_rebuild_and_results_stay_equal():
    rig = capsule_arm()
    rng = np.random.default_rng(7)
    model = Model(rig.vertices, rig.faces)
    bvh = DynamicBVH(model.positions, model.faces)
    assert bvh.degradation == pytest.approx(1.0)
    history = []
    for _ in range(1000):
        # faces thrown across the mesh: the leaves they stay in grow to the whole mesh
        moved = rng.choice(sorted(model.live), 5, replace=False)
        offsets = rng.normal(0, 1.0, (5, 1, 3))
        before = bvh.degradation
        for f, offset in zip(moved, offsets):
            model.faces[f] = model.add_vertices(model.tri(f) + offset)
        bvh.update(moved, model.positions, model.faces)
        history.append((before, bvh.rebuilds))
        if bvh.rebuilds:
            break
    assert bvh.rebuilds == 1, "the degradation never passed REBUILD_AT"
    assert max(h[0] for h in history) <= dyn.REBUILD_AT and bvh.degradation == pytest.approx(1.0)
    check_queries(bvh, model, rng)
    bvh.rebuild()
    assert bvh.rebuilds == 2
    check_queries(bvh, model, rng)


def test_progressive_incision_does_not_degrade():
    """Strokes along a line, pieces inside the removed faces: no rebuild, degradation stays ~1."""
    rig = capsule_arm(rings_per_segment=40, segments_around=48)
    rng = np.random.default_rng(3)
    model = Model(rig.vertices, rig.faces)
    bvh = DynamicBVH(model.positions, model.faces)
    for i in range(60):
        centre = np.array([0.3 + 2.4 * i / 60, 0.0, 0.25])
        near = bvh.faces_in_box(centre - 0.03, centre + 0.03)[:30]
        bvh.remove(near)
        ids = [g for f in near for g in model.pieces(f, model.tri(f).mean(axis=0), 3)]
        bvh.insert(ids, model.positions, model.faces)
    assert bvh.rebuilds == 0 and bvh.degradation < 1.2
    check_queries(bvh, model, rng)


def test_compiled_callers_get_the_same_answers():
    rig = capsule_arm()
    bvh = DynamicBVH(rig.vertices, rig.faces)
    bvh.remove([0, 5, 9])
    a, b = np.array([1.0, -1.0, 0.05]), np.array([1.2, 1.0, -0.05])
    lo, hi, normal = np.full(3, -1.0), np.full(3, 4.0), np.array([1.0, 0.0, 0.0])
    face, t, near = _compiled_queries(bvh.arrays, a, b, lo, hi, normal, 1.0, 0.05)
    assert (face, t) == bvh.first_hit(a, b) and face >= 0
    assert np.array_equal(np.sort(near), bvh.faces_near_plane(lo, hi, normal, 1.0, 0.05)) and len(near)
    # and the static BVH's kernel reads the same tree (no dead slot inside a leaf)
    assert static_first_hit(bvh.arrays, a, b)[1] == t


def test_the_tree_holds_no_geometry_and_int32_indices():
    """Its memory is the tree's (~65 bytes a face on the capsule: boxes and int32 indices), not a copy
    of the triangles (72 bytes a face alone); the spare room is allocated but not counted (unwritten)."""
    rig = capsule_arm(rings_per_segment=40, segments_around=48)
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    bvh = DynamicBVH(points, faces)
    assert bvh.arrays[7] is points and bvh.arrays[8] is faces        # the caller's arrays, not copies
    assert all(x.dtype == np.int32 for x in bvh.arrays[2:7])
    assert bvh.nbytes <= 70 * len(faces), bvh.nbytes / len(faces)
    copy = points.copy()
    bvh.use(copy, faces)
    assert bvh.arrays[7] is copy and bvh.first_hit([1.0, -1.0, 0.05], [1.2, 1.0, -0.05])[0] >= 0


def test_invalid_input_raises_and_leaves_the_bvh_alone():
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    bvh = DynamicBVH(points, faces)
    m, big = len(faces), 10 ** 4
    more = np.concatenate((faces, np.repeat(faces[:1], big + 2 - m, axis=0)))    # rows up to big + 1
    nan = points.copy()
    nan[faces[m - 1, 2], 0] = np.nan
    at_nan = more.copy()
    at_nan[big] = faces[m - 1]
    cases = [
        (lambda: DynamicBVH(points, faces[:0]), "faces"),
        (lambda: DynamicBVH(points[:, :2], faces), "positions"),
        (lambda: DynamicBVH(points, faces + len(points)), "faces"),
        (lambda: bvh.remove([m]), "not live"),
        (lambda: bvh.remove([3, 3]), "distinct"),
        (lambda: bvh.remove([-1]), "face_ids"),
        (lambda: bvh.remove([[1, 2]]), "shape"),
        (lambda: bvh.remove([0.5]), "integer"),
        (lambda: bvh.insert([4, big], points, more), "live faces"),
        (lambda: bvh.insert([big, big], points, more), "distinct"),
        (lambda: bvh.insert([m - 1, big], nan, more), "live faces"),
        (lambda: bvh.insert([big, big + 1], nan, at_nan), "non-finite"),
        (lambda: bvh.insert([len(more)], points, more), "no row"),
        (lambda: bvh.insert([2 ** 40], points, more), "face_ids"),
        (lambda: bvh.insert([big], points, more, near=[m + 9]), "near"),
        (lambda: bvh.insert([big], points, more, near=[0, 1]), "near"),
        (lambda: bvh.insert([big], points, more + len(points)), "must index"),
        (lambda: bvh.insert([big], points, more.astype(float)), "faces"),
        (lambda: bvh.insert([big], points[:, :2], more), "positions"),
        (lambda: bvh.update([1, 2], points[:, :2], faces), "positions"),
        (lambda: bvh.update([1, m - 1], nan, faces), "non-finite"),
        (lambda: bvh.update([m + 5, 2], points, faces), "not live"),
        (lambda: bvh.update([1, 2], points, faces[:2]), "no row"),
        (lambda: bvh.first_hit([0, 0, 0], [0, 0, 0]), "zero length"),
        (lambda: bvh.first_hit([0, 0], [1, 0, 0]), "a"),
        (lambda: bvh.faces_near_plane([0, 0, 0], [1, 1, 1], [0, 0, 1], 0.0, -1.0), "delta"),
        (lambda: bvh.faces_near_plane([0, 0, 0], [1, 1, 1], [0, 0, np.nan], 0.0, 0.1), "normal"),
        (lambda: bvh.faces_in_box([0, 0, 0], [1, 1]), "hi"),
        (lambda: bvh.triangle(m), "not live"),
    ]
    for call, word in cases:
        with pytest.raises(InvalidInputError, match=word):
            call()
    assert bvh.n_faces == m and bvh.rebuilds == 0
    assert bvh.arrays[7] is points and bvh.arrays[8] is faces       # a failed call keeps the arrays it had
    check_queries(bvh, Model(points, faces), np.random.default_rng(1), n_segments=5)


def test_callers_arrays_are_never_modified():
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices).copy(), np.asarray(rig.faces).copy()
    m = len(faces)
    grown_faces = np.concatenate((faces, faces[:2]))                  # faces m, m + 1: copies of 0, 1
    grown_points = np.concatenate((points, points[faces[5:7]].reshape(-1, 3) + 0.01))
    moved_faces = grown_faces.copy()
    moved_faces[5:7] = np.arange(len(points), len(points) + 6).reshape(2, 3)     # faces 5, 6 moved
    ids, moved_ids, gone = np.array([m, m + 1]), np.array([5, 6]), np.array([0, 1])
    a, b = np.array([1.0, -1.0, 0.0]), np.array([1.0, 1.0, 0.0])
    args = [points, faces, grown_faces, grown_points, moved_faces, ids, moved_ids, gone, a, b]
    saved = [x.copy() for x in args]
    bvh = DynamicBVH(points, faces)
    bvh.insert(ids, points, grown_faces)
    bvh.update(moved_ids, grown_points, moved_faces)
    bvh.remove(gone)
    bvh.first_hit(a, b), bvh.all_hits(a, b), bvh.faces_in_box(a, b + 1), bvh.triangle(m)[0].fill(0)
    bvh.faces_near_plane(a, b + 1, b, 0.0, 0.1)
    bvh.rebuild()
    for x, y in zip(args, saved):
        assert np.array_equal(x, y)
    assert np.array_equal(bvh.triangle(m), points[faces[0]])
    assert np.array_equal(bvh.triangle(6), grown_points[moved_faces[6]])
