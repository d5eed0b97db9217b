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


@kernel()
def _brute_hits(tri, a, b):
    """(t, i) of every crossing of a -> b with the triangles (k, 9), by the BVH's watertight test."""
    kx, ky, kz, sx, sy, sz = _shear(b - a)
    out = []
    for i in range(tri.shape[0]):
        t = _watertight(tri, i, a, kx, ky, kz, sx, sy, sz)
        if t >= 0.0 and t <= 1.0:
            out.append((t, i))
    return out


@kernel()
def _compiled_queries(arrays, a, b, lo, hi, normal, offset, delta):
    """The module's compiled queries, called from another kernel."""
    face, t = dyn_first_hit(arrays, a, b)
    return face, t, dyn_faces_near_plane(arrays, lo, hi, normal, offset, delta)


class Model:
    """The live triangles, by face id, as the test keeps them (the oracle's state)."""

    def __init__(self, points, faces):
        self.tri = {f: points[faces[f]].copy() for f in range(len(faces))}
        self.next_id = len(faces)

    def arrays(self):
        ids = np.array(sorted(self.tri), np.int64)
        return ids, np.array([self.tri[f] for f in ids]).reshape(-1, 9)


def random_edits(bvh, model, rng, steps, scale):
    """Strokes: remove a few faces near a random one, insert 1-3 pieces of each (inside it), move a
    few faces by up to ``scale``."""
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
        new_ids, new_tri, parents = [], [], []
        for f in removed:
            c = model.tri.pop(f)
            w = rng.dirichlet(np.ones(3))
            m = w @ c                     # a point inside: the fan of pieces around it covers the face
            for j in range(rng.integers(1, 4)):
                new_ids.append(model.next_id)
                new_tri.append(np.array([c[j], c[(j + 1) % 3], m]))
                parents.append(f)
                model.tri[model.next_id] = new_tri[-1]
                model.next_id += rng.integers(1, 50)     # sparse ids, never reused
        if beside:
            bvh.insert(np.array(new_ids), np.array(new_tri), near=np.array(parents))
            bvh.remove(removed)
        else:
            bvh.insert(np.array(new_ids), np.array(new_tri))
        moved = near[len(removed):len(removed) + rng.integers(0, 5)]
        if len(moved):
            corners = np.array([model.tri[f] for f in moved]) + rng.normal(0, scale, (len(moved), 3, 3))
            bvh.update(moved, corners)
            for f, c in zip(moved, corners):
                model.tri[f] = c


def check_queries(bvh, model, rng, n_segments=20):
    """Every query against brute force over the model's live triangles and against a fresh TriangleBVH."""
    ids, tri = model.arrays()
    assert bvh.n_faces == len(ids)
    fresh = TriangleBVH(tri.reshape(-1, 3), np.arange(3 * len(ids)).reshape(-1, 3))
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    for _ in range(n_segments):
        a, b = rng.uniform(lo - 0.1, hi + 0.1), rng.uniform(lo - 0.1, hi + 0.1)
        expected = sorted((t, ids[i]) for t, i in _brute_hits(tri, a, b))
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
    bvh = DynamicBVH(rig.vertices, rig.faces)
    model = Model(np.asarray(rig.vertices), np.asarray(rig.faces))
    random_edits(bvh, model, rng, steps, scale)
    check_queries(bvh, model, rng)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), m=st.integers(1, 40), steps=st.integers(0, 25),
       capacity=st.sampled_from([0, 3, None]))
def test_edits_on_random_soups_match_brute_force(seed, m, steps, capacity):
    """Small random triangle soups, no spare room at first (the arrays must grow)."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (3 * m, 3))
    faces = rng.permutation(3 * m).reshape(m, 3)
    bvh = DynamicBVH(points, faces, capacity=capacity)
    model = Model(points, faces)
    random_edits(bvh, model, rng, steps, 0.3)
    if model.tri:
        check_queries(bvh, model, rng)


def test_equal_t_picks_the_lowest_face_id():
    """Coincident triangles wherever they sit in the tree: the lowest live id wins."""
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    bvh = DynamicBVH(points, faces)
    f = 100
    c = points[faces[f]]
    inside, normal = c.mean(axis=0), np.cross(c[1] - c[0], c[2] - c[0])
    a, b = inside - normal / np.linalg.norm(normal) * 1e-3, inside + normal / np.linalg.norm(normal) * 1e-3
    bvh.insert([10 ** 6, 10 ** 6 + 7], np.array([c, c]))
    assert bvh.first_hit(a, b)[0] == f and bvh.first_hit(b, a)[0] == f
    bvh.remove([f])
    assert bvh.first_hit(a, b)[0] == 10 ** 6
    bvh.insert([3 * 10 ** 6], c[None])        # more copies fill the leaf and split it
    bvh.insert(np.empty(0, np.int64), np.empty((0, 3, 3)))
    for k in range(12):
        bvh.insert([2 * 10 ** 6 + k], c[None])
    assert bvh.first_hit(a, b)[0] == 10 ** 6
    bvh.remove([10 ** 6])
    assert bvh.first_hit(a, b)[0] == 10 ** 6 + 7
    two = DynamicBVH(np.vstack([c, c]), [[3, 4, 5], [0, 1, 2]])
    assert two.first_hit(a, b)[0] == 0
    faces_hit, ts = two.all_hits(a, b)
    assert faces_hit.tolist() == [0, 1] and ts[0] == ts[1]


def test_degradation_triggers_a_rebuild_and_results_stay_equal():
    rig = capsule_arm()
    rng = np.random.default_rng(7)
    bvh = DynamicBVH(rig.vertices, rig.faces)
    model = Model(np.asarray(rig.vertices), np.asarray(rig.faces))
    assert bvh.degradation == pytest.approx(1.0)
    history = []
    for _ in range(1000):
        # faces thrown across the mesh: the leaves they stay in grow to the whole mesh
        moved = rng.choice(sorted(model.tri), 5, replace=False)
        corners = np.array([model.tri[f] for f in moved]) + rng.normal(0, 1.0, (5, 1, 3))
        before = bvh.degradation
        bvh.update(moved, corners)
        for f, c in zip(moved, corners):
            model.tri[f] = c
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
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    bvh = DynamicBVH(points, faces)
    model = Model(points, faces)
    for i in range(60):
        centre = np.array([0.3 + 2.4 * i / 60, 0.0, 0.25])
        near = bvh.faces_in_box(centre - 0.03, centre + 0.03)[:30]
        bvh.remove(near)
        pieces = []
        for f in near:
            c = model.tri.pop(f)
            m = c.mean(axis=0)
            pieces += [np.array([c[j], c[(j + 1) % 3], m]) for j in range(3)]
        ids = np.arange(model.next_id, model.next_id + len(pieces))
        model.next_id += len(pieces)
        bvh.insert(ids, np.array(pieces))
        model.tri.update(zip(ids.tolist(), pieces))
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


def test_invalid_input_raises_and_leaves_the_bvh_alone():
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    bvh = DynamicBVH(points, faces)
    good = points[faces[:2]]
    nan = good.copy()
    nan[1, 2, 0] = np.nan
    cases = [
        (lambda: DynamicBVH(points, faces[:0]), "faces"),
        (lambda: DynamicBVH(points[:, :2], faces), "positions"),
        (lambda: DynamicBVH(points, faces + len(points)), "faces"),
        (lambda: bvh.remove([len(faces)]), "not live"),
        (lambda: bvh.remove([3, 3]), "distinct"),
        (lambda: bvh.remove([-1]), "face_ids"),
        (lambda: bvh.remove([[1, 2]]), "shape"),
        (lambda: bvh.remove([0.5]), "integer"),
        (lambda: bvh.insert([4, 10 ** 7], good), "live faces"),
        (lambda: bvh.insert([10 ** 7, 10 ** 7], good), "distinct"),
        (lambda: bvh.insert([10 ** 7, 10 ** 7 + 1], nan), "non-finite"),
        (lambda: bvh.insert([10 ** 7], good), "corners"),
        (lambda: bvh.insert([2 ** 40], good[:1]), "face_ids"),
        (lambda: bvh.insert([10 ** 7], good[:1], near=[len(faces) + 9]), "near"),
        (lambda: bvh.insert([10 ** 7], good[:1], near=[0, 1]), "near"),
        (lambda: bvh.update([1, 2], good[:, :, :2]), "corners"),
        (lambda: bvh.update([1, 2], np.full((2, 3, 3), np.inf)), "non-finite"),
        (lambda: bvh.update([len(faces) + 5, 2], good), "not live"),
        (lambda: bvh.first_hit([0, 0, 0], [0, 0, 0]), "zero length"),
        (lambda: bvh.first_hit([0, 0], [1, 0, 0]), "a"),
        (lambda: bvh.faces_near_plane([0, 0, 0], [1, 1, 1], [0, 0, 1], 0.0, -1.0), "delta"),
        (lambda: bvh.faces_near_plane([0, 0, 0], [1, 1, 1], [0, 0, np.nan], 0.0, 0.1), "normal"),
        (lambda: bvh.faces_in_box([0, 0, 0], [1, 1]), "hi"),
        (lambda: bvh.triangle(len(faces)), "not live"),
    ]
    for call, word in cases:
        with pytest.raises(InvalidInputError, match=word):
            call()
    assert bvh.n_faces == len(faces) and bvh.rebuilds == 0
    check_queries(bvh, Model(points, faces), np.random.default_rng(1), n_segments=5)


def test_callers_arrays_are_never_modified():
    rig = capsule_arm()
    points, faces = np.asarray(rig.vertices).copy(), np.asarray(rig.faces).copy()
    ids, corners = np.array([7000, 7001]), points[faces[:2]].copy()
    moved_ids, moved = np.array([5, 6]), points[faces[5:7]] + 0.01
    gone, a, b = np.array([0, 1]), np.array([1.0, -1.0, 0.0]), np.array([1.0, 1.0, 0.0])
    args = [points, faces, ids, corners, moved_ids, moved, gone, a, b]
    saved = [x.copy() for x in args]
    bvh = DynamicBVH(points, faces)
    bvh.insert(ids, corners)
    bvh.update(moved_ids, moved)
    bvh.remove(gone)
    bvh.first_hit(a, b), bvh.all_hits(a, b), bvh.faces_in_box(a, b + 1), bvh.triangle(7000)[0].fill(0)
    bvh.faces_near_plane(a, b + 1, b, 0.0, 0.1)
    bvh.rebuild()
    for x, y in zip(args, saved):
        assert np.array_equal(x, y)
    assert np.array_equal(bvh.triangle(7000), corners[0])
