"""``_shared.ids.distinct``: the sorted distinct ids by marks over their span, exactly ``np.unique``'s
answer, for ids close together (marks) and far apart (a sort), in any shape."""
import numpy as np
from hypothesis import given, strategies as st
from hypothesis.extra.numpy import arrays

from cgaskin._shared.ids import distinct


@given(arrays(np.int64, st.tuples(st.integers(0, 40), st.integers(1, 3)),
              elements=st.one_of(st.integers(0, 50), st.integers(0, 2**40))))
def test_distinct_is_unique(ids):
    got = distinct(ids)
    assert got.dtype == np.int64
    assert np.array_equal(got, np.unique(ids))


def test_distinct_leaves_its_input_alone():
    ids = np.array([[5, 3, 5], [9, 3, 1]])
    before = ids.copy()
    assert distinct(ids).tolist() == [1, 3, 5, 9]
    assert np.array_equal(ids, before)
