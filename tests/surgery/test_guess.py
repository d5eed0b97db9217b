"""Where a blade meets the surface (``locate._meet``, which a stroke's guess and ``locate`` share) reads
the boundary vertices near the blade through the BVH (the whole surface) or from a list (a patch); both
must find the vertex that a scan of every boundary vertex finds, ties and all."""
import math

import numpy as np
from hypothesis import given, strategies as st
from numba import njit

import cgaskin
from cgaskin.surgery.bvh import TriangleBVH
from cgaskin.surgery.tear.locate import _boundary_near
from cgaskin.surgery.tear.rig_source import RigSource


@njit
def _near(bvh, flags, a, b, t_max, snap):
    return _boundary_near(bvh, bvh[7], bvh[8], flags, np.zeros(0, np.int64), a, b, t_max, snap)


@njit
def _near_list(bvh, boundary, a, b, t_max, snap):
    return _boundary_near(bvh, bvh[7], bvh[8], np.zeros(0, np.bool_), boundary, a, b, t_max, snap)


@njit
def _scan(a, b, t_max, boundary, positions, snap):
    """The oracle: every boundary vertex (ascending ids), the one within ``snap`` of a -> b with the
    smallest parameter t < t_max, the lowest id among equal t."""
    d = b - a
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    best, best_t = -1, t_max
    for w in boundary:
        p = positions[w]
        t = min(max(((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / dd, 0.0), 1.0)
        if t < best_t and math.sqrt((a[0] + t * d[0] - p[0]) ** 2 + (a[1] + t * d[1] - p[1]) ** 2
                                    + (a[2] + t * d[2] - p[2]) ** 2) <= snap:
            best, best_t = w, t
    return best, best_t


def _torn_capsule():
    """The built-in capsule with an opened slit (boundary vertices on both sides of it) and its
    BVH, boundary flags and positions as a stroke reads them."""
    rig = cgaskin.capsule_arm()
    blades = [([x, 0.35, 0.03], [x, 0.0, 0.03]) for x in (0.6, 0.9, 1.2)]
    for start, end in zip(blades, blades[1:]):
        rig = cgaskin.tear(rig, start, end, opening=0.02)
    source = RigSource(rig, None, None)
    bvh = TriangleBVH(source.positions, source.faces)
    return source.positions, source.boundary, tuple(bvh._arrays)


POSITIONS, FLAGS, BVH = _torn_capsule()
BOUNDARY = np.flatnonzero(FLAGS)


@given(st.integers(0, len(BOUNDARY) - 1), st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1),
       st.floats(0.0, 1.0), st.sampled_from([1e-9, 1e-3, 0.02, 0.1]), st.booleans())
def test_the_first_boundary_vertex_near_a_blade_is_the_one_a_full_scan_finds(target, dx, dy, dz, t_max, snap,
                                                                            through):
    # a blade towards a boundary vertex (through it, or passing it at a random offset)
    p = POSITIONS[BOUNDARY[target]]
    offset = np.zeros(3) if through else 0.05 * np.array([dx, dy, dz])
    a = p + np.array([0.0, 0.6, 0.2]) + offset
    b = p - np.array([0.0, 0.6, 0.2]) + offset
    found = _scan(a, b, t_max, BOUNDARY, POSITIONS, snap)
    assert _near(BVH, FLAGS, a, b, t_max, snap) == found                  # through the BVH (the whole surface)
    assert _near_list(BVH, BOUNDARY[::-1].copy(), a, b, t_max, snap) == found   # over a list (a patch), any order
    assert BOUNDARY.size > 20                               # the slit's sides are there to find


def test_ties_go_to_the_lowest_vertex_as_in_the_scan():
    # two boundary vertices at the same distance along the blade: the blade runs between twins (a
    # slit's two sides sit on one position before it opens); here: any vertex and a blade along the
    # plane through it and its nearest boundary neighbour, both within snap
    p, q = POSITIONS[BOUNDARY[0]], POSITIONS[BOUNDARY[1]]
    middle = 0.5 * (p + q)
    a, b = middle + np.array([0.0, 1.0, 0.0]), middle - np.array([0.0, 1.0, 0.0])
    snap = float(np.linalg.norm(p - q))
    found = _near(BVH, FLAGS, a, b, 1.0, snap)
    assert found == _scan(a, b, 1.0, BOUNDARY, POSITIONS, snap)
    assert found[0] >= 0
