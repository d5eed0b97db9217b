"""Internal faults of a tear stroke are not user errors (issue 22, item 16): the walk's node table grows
instead of stopping short (which read as "use shorter strokes"), and a patch that does not settle is
an ``InternalError`` that says it is a bug (it was an ``AssertionError``)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numba import njit

from cgaskin import capsule_arm, tear_stroke
from cgaskin.errors import CgaskinError, InternalError
from cgaskin.surgery.tear import splice
from cgaskin.surgery.tear.guess import _guess
from cgaskin.surgery.tear.records import OK
from cgaskin.surgery.tear.rig_source import RigSource
from cgaskin.surgery.tear.settle import _settle
from cgaskin.surgery.tear.walk import _walk_within
from cgaskin.tolerances import tol

from tests.helpers.tear_checks import capsule_blades


@njit
def _walks(source, blades, snap, min_sine, posing, capacities):
    """Steps 2-4 of ``splice._stroke`` on a rest source (``records.StrokeSource`` as a tuple), the walk
    run once per first node-table size in ``capacities`` and once as the stroke runs it (a node per
    patch face and edge): (found, path_int, path_float) of each, the stroke's last; empty when the guess
    misses or the patch does not settle."""
    bvh, boundary, _, _, _, _, _, _, _, _, _, diagonal = source
    snap = snap * diagonal
    status, plane, margin, hit_faces = _guess(bvh, boundary, blades, snap, min_sine)
    out = [(False, np.empty((0, 4), np.int64), np.empty((0, 4)))]
    out.clear()
    if status != OK:
        return out
    settled, patch, tree, ends = _settle(source, blades, plane, plane.any(), margin, snap, min_sine, posing)
    if not settled:
        return out
    _, _, patch_faces, patch_positions, _, mesh, _, _, _ = patch
    _, ends_int, ends_pos, _, ends_faces, ends_plane, sides = ends
    patch_bvh = (tree[0], tree[1], tree[2], tree[3], tree[4], tree[5], tree[6], patch_positions, patch_faces)
    region = (blades[0], blades[1], blades[2], blades[3])
    sizes = np.empty(capacities.shape[0] + 1, np.int64)
    sizes[:-1], sizes[-1] = capacities, mesh[1].shape[0] + mesh[3].shape[0] + 4
    for capacity in sizes:
        out.append(_walk_within(mesh, sides, ends_plane, (ends_int[0, 0], ends_int[0, 1], ends_pos[0]),
                                (ends_int[1, 0], ends_int[1, 1], ends_pos[1]), patch_bvh, region, ends_faces, snap,
                                capacity))
    return out


_RIG = None


def _long_stroke():
    """A fine capsule (8 rings of quads per 0.1 along x) and a stroke over most of its length, whose path
    crosses hundreds of edges: far more nodes than a small first node table holds."""
    global _RIG
    if _RIG is None:
        _RIG = capsule_arm(rings_per_segment=80, segments_around=24)
    return _RIG, np.concatenate(capsule_blades(0.1, 2.9))


@settings(max_examples=12, deadline=None)
@given(capacities=st.lists(st.integers(1, 300), min_size=1, max_size=4))
def test_walk_grows_its_node_table(capacities):
    rig, blades = _long_stroke()
    source = RigSource(rig, None, None)
    walks = _walks(tuple(splice.stroke_source(source)), blades, tol.snap, tol.min_sine, source.posing,
                   np.array(capacities, np.int64))
    assert len(walks) == len(capacities) + 1          # the stroke's patch settled
    found, path_int, path_float = walks[-1]
    assert found and len(path_int) > 300            # the long way: far more nodes than a small table
    for capacity, (found_small, int_small, float_small) in zip(capacities, walks):
        assert found_small, f"the walk stopped short with a first node table of {capacity}"
        np.testing.assert_array_equal(int_small, path_int)
        np.testing.assert_array_equal(float_small, path_float)


def test_long_stroke_tears_along_its_whole_length():
    rig, blades = _long_stroke()
    result = tear_stroke(rig, blades[:2], blades[2:])
    assert len(result.points) > 300
    assert result.points[0, 0] == pytest.approx(0.1, abs=0.02) and result.points[-1, 0] == pytest.approx(2.9, abs=0.02)
    assert np.all(np.diff(result.points[:, 0]) > 0)          # one way along the capsule, no detour


def test_unsettled_patch_is_an_internal_error(monkeypatch):
    """A patch that does not settle (``settle.ROUNDS`` ran out: a bug) reaches the user as an
    ``InternalError`` that says so, not an ``AssertionError``."""
    real = splice._stroke

    def unsettled(*args):
        status, hit_faces, located = real(*args)
        settled, ends, path, spliced = located
        assert settled
        return status, hit_faces, (False, ends, path, None)

    monkeypatch.setattr(splice, "_stroke", unsettled)
    rig = capsule_arm()
    with pytest.raises(InternalError, match="bug in cgaskin") as caught:
        tear_stroke(rig, *capsule_blades(1.0, 1.5))
    assert isinstance(caught.value, CgaskinError) and not isinstance(caught.value, (AssertionError, ValueError))
    assert "report" in str(caught.value) and "\n" not in str(caught.value)
