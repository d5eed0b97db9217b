"""A cut keeps its working arrays per rig (``cgaskin._shared.memory.Reusable``) and makes its outputs on
recycled memory (``recycled_empty``): later cuts of the same rig, in any order, in threads, give what a
cut of a rig never cut before gives, the arrays a cut returns are its own (never the kept ones), and
the outputs the caller still holds never change.
"""
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from cgaskin import Rig, capsule_arm, cut_details
from cgaskin._shared import memory
from cgaskin._shared.cache import rig_cached

# (one plane misses the capsule on purpose; a filter set inside threads would race with the others)
pytestmark = pytest.mark.filterwarnings("ignore::cgaskin.PlaneMissesMeshWarning")

#: (normal, point, posed, cap): planes that cross the capsule, one through a ring of its vertices, and
#: one that misses it
CUTS = [([1, 0.2, 0.1], [1.3, 0.01, 0.02], False, False),
        ([1, 0, 0], [0.25, 0, 0], False, True),
        ([0.3, 1, 0.2], [1.5, 0.05, 0], True, False),
        ([1, 0, 0], [10.0, 0, 0], False, False),
        ([-1, 0.1, 0.3], [2.1, 0, 0.05], True, True)]


def _fresh(rig) -> Rig:
    """The same mesh as a rig never cut (nothing cached for it)."""
    return Rig(vertices=rig.vertices, faces=rig.faces, joints=rig.joints, weights=rig.weights,
               skeleton=rig.skeleton, clips=rig.clips, attributes=dict(rig.attributes))


def _cut(rig, normal, point, posed, cap):
    pose = rig.rest_pose().rotate(1, [0, 0, 1], 0.4) if posed else None
    return cut_details(rig, normal, point, pose=pose, cap=cap)


def _arrays(result) -> list:
    out = [result.edge_vertices, result.edge_t, result.new_positions, *result.sources]
    for half in (result.positive, result.negative):
        out += [half.vertices, half.faces, half.joints, half.weights, *half.attributes.values()]
    return out


def _same(a, b) -> bool:
    return all(x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x, y)
               for x, y in zip(_arrays(a), _arrays(b), strict=True))


@pytest.fixture(params=["large outputs recycled", "every output recycled"])
def recycling(request, monkeypatch):
    """As cgaskin runs (only outputs of 4 MB and more recycled: none of the capsule's), and with every
    output on recycled memory."""
    if request.param == "every output recycled":
        monkeypatch.setattr(memory, "RECYCLED_FROM", 1)
    memory.release_free_memory()
    yield
    memory.release_free_memory()


def test_repeated_cuts_of_one_rig_match_cuts_of_fresh_rigs(recycling):
    rig = capsule_arm()
    expected = [_cut(_fresh(rig), *c) for c in CUTS]
    for order in (CUTS, CUTS[::-1], CUTS + CUTS):
        for c in order:
            assert _same(_cut(rig, *c), expected[CUTS.index(c)])


def test_a_cut_leaves_its_working_arrays_as_it_found_them():
    rig = capsule_arm()
    for c in CUTS:
        _cut(rig, *c)
        work = rig_cached(rig, "cut.scratch", None).take()
        assert not work.used.any()
        assert (work.new_of_edge == -1).all()


def test_cuts_in_threads_match_cuts_one_after_another(recycling):
    rig = capsule_arm()
    expected = [_cut(_fresh(rig), *c) for c in CUTS]
    jobs = CUTS * 4
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda c: _cut(rig, *c), jobs))
    for c, result in zip(jobs, results):
        assert _same(result, expected[CUTS.index(c)])


def test_returned_arrays_share_no_memory_with_the_kept_ones_or_each_other(recycling):
    rig = capsule_arm()
    first = _cut(rig, *CUTS[0])
    second = _cut(rig, *CUTS[0])
    kept = rig_cached(rig, "cut.scratch", None).take()
    for a in _arrays(first):
        for b in list(kept) + _arrays(second):
            assert not np.shares_memory(a, b)


def test_outputs_held_by_the_caller_survive_later_cuts(recycling):
    rig = capsule_arm()
    held = [_cut(rig, *c) for c in CUTS]                 # all held: every later cut takes new memory
    snapshot = [[a.copy() for a in _arrays(r)] for r in held]
    views = [held[0].positive.vertices[::3], held[1].negative.faces.T]
    pinned = [v.copy() for v in views]
    del held[2:]                                         # dropped: their memory serves the next cuts
    for c in CUTS + CUTS[::-1]:
        _cut(rig, *c)
    for result, arrays in zip(held, snapshot):
        assert all(np.array_equal(a, b) for a, b in zip(_arrays(result), arrays, strict=True))
    assert all(np.array_equal(v, p) for v, p in zip(views, pinned))
