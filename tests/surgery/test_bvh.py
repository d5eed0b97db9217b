"""The triangle BVH the tear casts its scalpel with (cgaskin.TriangleBVH): first hits against brute
force, watertight through shared vertices and edges, its cache and checks.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cgaskin import TriangleBVH
from cgaskin.errors import InvalidInputError

from tests.helpers.tear_checks import get_rig


def brute_force_hits(points, faces, a, b):
    """(t, face) of every crossing by Möller–Trumbore, two-sided."""
    out = []
    d = b - a
    for f, (p, q, r) in enumerate(points[faces]):
        e1, e2 = q - p, r - p
        h = np.cross(d, e2)
        det = e1 @ h
        if abs(det) < 1e-300:
            continue
        s = a - p
        u = (s @ h) / det
        k = np.cross(s, e1)
        v = (d @ k) / det
        t = (e2 @ k) / det
        if u >= 0 and v >= 0 and u + v <= 1 and 0 <= t <= 1:
            out.append((t, f))
    return sorted(out)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), flip=st.booleans())
def test_bvh_first_hit_matches_brute_force(seed, flip):
    rig = get_rig("capsule")
    rng = np.random.default_rng(seed)
    faces = np.asarray(rig.faces)[:, ::-1] if flip else np.asarray(rig.faces)    # either orientation
    bvh = TriangleBVH(rig.vertices, faces)
    lo, hi = rig.vertices.min(axis=0) - 0.2, rig.vertices.max(axis=0) + 0.2
    a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
    expected = brute_force_hits(rig.vertices, faces, a, b)
    face, t = bvh.first_hit(a, b)
    if not expected:
        assert face == -1
        return
    assert abs(t - expected[0][0]) <= 1e-12
    hit_faces, ts = bvh.all_hits(a, b)
    assert len(hit_faces) >= len({round(e[0], 9) for e in expected})
    assert np.all(np.diff(ts) >= 0)


def test_bvh_is_watertight_through_vertices_and_edges():
    """Segments aimed exactly at shared vertices and edge midpoints of a grid never slip through."""
    x, y = np.meshgrid(np.arange(6.0), np.arange(6.0))
    points = np.stack([x.ravel(), y.ravel(), np.zeros(36)], axis=1)
    faces = []
    for i in range(5):
        for j in range(5):
            v = 6 * i + j
            faces += [[v, v + 1, v + 7], [v, v + 7, v + 6]]
    bvh = TriangleBVH(points, faces)
    targets = [points[14], (points[14] + points[15]) / 2, (points[14] + points[21]) / 2]
    for p in targets:
        for tilt in ([0, 0, 0], [0.3, -0.2, 0], [1e-9, 0, 0]):
            a, b = p + [0, 0, 1] + np.array(tilt), p - [0, 0, 1] - np.array(tilt)
            face, t = bvh.first_hit(a, b)
            assert face >= 0 and abs(t - 0.5) < 1e-12


def test_bvh_checks():
    rig = get_rig("capsule")
    with pytest.raises(InvalidInputError):
        TriangleBVH(rig.vertices, np.zeros((0, 3), int))
    with pytest.raises(InvalidInputError):
        TriangleBVH(rig.vertices[:, :2], rig.faces)
    bvh = TriangleBVH(rig.vertices, rig.faces)
    with pytest.raises(InvalidInputError):
        bvh.first_hit([0, 0, 0], [0, 0, 0])
    np.testing.assert_array_equal(bvh.triangle(7), rig.vertices[rig.faces[7]])


def test_bvh_reads_its_own_copies_of_the_mesh():
    """The BVH holds positions and faces (float64, int64 copies) and int32 tree indices, no corner copy:
    changing the caller's arrays afterwards changes none of its answers."""
    rig = get_rig("capsule")
    points, faces = np.array(rig.vertices), np.array(rig.faces, np.int32)
    bvh = TriangleBVH(points, faces)
    a, b = np.array([1.0, -1.0, 0.05]), np.array([1.2, 1.0, -0.05])
    face, t = bvh.first_hit(a, b)
    assert face >= 0
    points += 5.0
    faces[:] = faces[::-1]
    assert bvh.first_hit(a, b) == (face, t)
    np.testing.assert_array_equal(bvh.triangle(face), rig.vertices[rig.faces[face]])
    arrays = bvh._arrays
    assert arrays.positions.dtype == np.float64 and arrays.faces.dtype == np.int64
    assert all(x.dtype == np.int32 for x in arrays[2:7]) and len(arrays.order) == len(faces)
