"""The kernel tests' oracles themselves: clifford's conventions (design.md section 2) and the bridge
between versor arrays and clifford multivectors (cgaskin.versor.to_clifford / from_clifford).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given

from cgaskin import versor as V
from cgaskin.errors import InvalidInputError
from cgaskin.generated.layout import VERSOR_BLADES
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import (I3, ONE, cl_apply, cl_blade, cl_dilator, cl_exp, cl_rotor,
                                          cl_translator, cl_vector, cl_versor, clifford_point_tol, e1,
                                          einf, eo, euclid)
from tests.helpers.tolerances import TOL, rel_err

# ==== the oracles themselves ================================================================================
def test_clifford_oracle_conventions():
    # e0 . e-inf = -1 and both are null (design.md section 2)
    assert (eo | einf)[()] == -1.0 and (einf * einf).value.max() == 0 and (eo * eo).value.max() == 0
    # a positive angle is right-handed: e1 rotated by +90 degrees about e3 is e2
    r = cl_rotor([0, 0, 1], math.pi / 2)
    np.testing.assert_allclose(euclid(r * e1 * ~r), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(cl_apply(r, [1.0, 0, 0]), [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(cl_apply(cl_rotor([1, 0, 0], math.pi / 2), [0, 1.0, 0]), [0, 0, 1], atol=1e-15)
    # translator and dilator
    np.testing.assert_allclose(cl_apply(cl_translator([1, -2, 3]), [0.5, 0.5, 0.5]), [1.5, -1.5, 3.5], atol=1e-14)
    for s in (0.01, 0.5, 3.0, 100.0):
        np.testing.assert_allclose(cl_apply(cl_dilator(s), [0.1, 0.2, -0.3]), np.multiply(s, [0.1, 0.2, -0.3]),
                                   rtol=clifford_point_tol(0.3 * s))
        d = cl_exp(-0.5 * math.log(s) * (einf ^ eo))
        assert rel_err(d.value, cl_dilator(s).value) <= 1e-14
    # T R D applies D first, then R, then T
    sim = S.Similarity(np.array([0.0, 0.0, 1.0]), math.pi / 2, np.array([1.0, 2.0, 3.0]), 2.0)
    np.testing.assert_allclose(cl_apply(cl_versor(sim), [1.0, 0, 0]), sim.apply([1.0, 0, 0]), atol=1e-13)
    # Taylor exp of a rotation bivector is the rotor
    n = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    assert rel_err(cl_exp(-0.5 * 2.5 * (cl_vector(n) * I3)).value, cl_rotor(n, 2.5).value) <= 1e-14


@given(S.coefficient_arrays(12))
def test_to_clifford_matches_hand_built(arr):
    hand = sum((float(c) * cl_blade(name) for c, name in zip(arr, VERSOR_BLADES)), 0.0 * ONE)
    got = V.to_clifford(arr)
    assert rel_err(got.value, hand.value, max(1.0, np.abs(arr).max())) <= TOL.table
    batch = V.to_clifford(np.stack([arr, 2 * arr]))
    assert isinstance(batch, list) and len(batch) == 2
    assert rel_err(batch[1].value, 2 * hand.value, max(1.0, np.abs(arr).max())) <= TOL.table


@given(S.coefficient_arrays(12))
def test_from_clifford_matches_hand_built(arr):
    hand = sum((float(c) * cl_blade(name) for c, name in zip(arr, VERSOR_BLADES)), 0.0 * ONE)
    assert rel_err(V.from_clifford(hand), arr, max(1.0, np.abs(arr).max())) <= 1e-14
    assert rel_err(V.from_clifford(V.to_clifford(arr)), arr, max(1.0, np.abs(arr).max())) <= 1e-14
    with pytest.raises(InvalidInputError):
        V.from_clifford(hand + 0.5 * e1)                          # a vector part is not in the type
    with pytest.raises(InvalidInputError):
        V.from_clifford(hand + 0.5 * (e1 ^ eo))
