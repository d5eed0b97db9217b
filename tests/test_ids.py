"""``_shared.ids``: the sorted distinct ids by marks over their span, exactly ``np.unique``'s answer
(``distinct``) or ``np.sort``'s for distinct ids (``ascending``), for few ids and many, close together
(marks) and far apart (a sort), in any shape."""
import numpy as np
from hypothesis import given, strategies as st
from hypothesis.extra.numpy import arrays

from cgaskin._shared.ids import ascending, distinct


@given(arrays(np.int64, st.tuples(st.integers(0, 40), st.integers(1, 3)),
              elements=st.one_of(st.integers(0, 50), st.integers(0, 2**40))))
def test_distinct_is_unique(ids):
    got = distinct(ids)
    assert got.dtype == np.int64
    assert np.array_equal(got, np.unique(ids))


@given(st.sets(st.one_of(st.integers(0, 3000), st.integers(0, 2**40)), max_size=2000))
def test_ascending_sorts_distinct_ids(ids):
    ids = np.random.default_rng(len(ids)).permutation(np.array(sorted(ids), np.int64))
    assert np.array_equal(ascending(ids), np.sort(ids))


def test_distinct_leaves_its_input_alone():
    ids = np.array([[5, 3, 5], [9, 3, 1]])
    before = ids.copy()
    assert distinct(ids).tolist() == [1, 3, 5, 9]
    assert np.array_equal(ids, before)


@given(st.integers(600, 5000), st.sampled_from([1, 3, 60, 10_000]), st.integers(0, 2**20), st.integers(0, 2**31))
def test_many_ids_marked_or_sorted(count, spread, low, seed):
    """Past ``FEW`` ids: marks over a span up to ``SPREAD`` times their count, a sort beyond."""
    rng = np.random.default_rng(seed)
    ids = low + rng.integers(0, spread * count, count)
    assert np.array_equal(distinct(ids), np.unique(ids))
    once = np.unique(ids)
    assert np.array_equal(ascending(rng.permutation(once)), once)
