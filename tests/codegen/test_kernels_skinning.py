"""Skinning kernels against clifford, float64 matrices and numpy LBS: the point sandwich, the versor's
affine map, affine_point and the per-vertex blend loops (codegen/kernels_skinning.py).
"""
from __future__ import annotations

import numpy as np
from hypothesis import given

from cgaskin.generated import kernels as K
from cgaskin.generated import skinning as SK
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import (call, cl_apply, cl_versor, clifford_point_tol, covers,
                                          moderate_scale_versors, record, versor_coefficients)
from tests.helpers.tolerances import TOL, rel_err

# ==== points ===================================================================================================
@covers("sandwich_versor_point")
@given(moderate_scale_versors, S.moderate_points())
def test_sandwich_versor_point_vs_clifford(sim, x):
    v = versor_coefficients(sim)
    got = call(K.sandwich_versor_point, v, x)
    expected = cl_apply(cl_versor(sim), x)
    mag = max(1.0, float(np.abs(expected).max()), sim.scale * float(np.abs(x).max()))
    assert record("sandwich_versor_point (clifford)", rel_err(got, expected, mag)) <= clifford_point_tol(mag)


@given(S.versors(), S.points())
def test_sandwich_versor_point_large(sim, x):
    got = call(K.sandwich_versor_point, sim.versor(), x)
    expected = sim.apply(x)
    mag = max(sim.magnitude, sim.scale * float(np.abs(x).max()))
    assert record("sandwich_versor_point", rel_err(got, expected, mag)) <= TOL.large


@covers("versor_to_affine")
@given(moderate_scale_versors)
def test_versor_to_affine_vs_clifford(sim):
    a = call(K.versor_to_affine, versor_coefficients(sim)).reshape(3, 4)
    cv = cl_versor(sim)
    origin = cl_apply(cv, np.zeros(3))
    columns = [cl_apply(cv, np.eye(3)[j]) - origin for j in range(3)]
    expected = np.column_stack(columns + [origin])
    mag = max(1.0, sim.magnitude)
    assert record("versor_to_affine (clifford)", rel_err(a, expected, mag)) <= clifford_point_tol(mag + sim.scale)


@given(S.versors())
def test_versor_to_affine_large(sim):
    a = call(K.versor_to_affine, sim.versor()).reshape(3, 4)
    err = max(rel_err(a[:, :3], sim.linear(), sim.scale), rel_err(a[:, 3], sim.translation, sim.magnitude))
    assert record("versor_to_affine", err) <= TOL.large


@covers("affine_point")
@given(S.coefficient_arrays(12, 100.0), S.points())
def test_affine_point(a, x):
    got = call(K.affine_point, a, x)
    m = a.reshape(3, 4)
    expected = m[:, :3] @ x + m[:, 3]
    scale = max(1e-300, float(np.max(np.abs(m[:, :3]) @ np.abs(x) + np.abs(m[:, 3]))))
    assert record("affine_point", rel_err(got, expected, scale)) <= TOL.kernel


# ==== skinning loops ==========================================================================================
def _numpy_lbs(rest, joints, weights, affines):
    a = affines.reshape(-1, 3, 4)
    blended = np.einsum("nk,nkij->nij", weights, a[joints])
    return np.einsum("nij,nj->ni", blended[:, :, :3], rest) + blended[:, :, 3]


@covers("skin_blend", "skin_blend_parallel")
@given(S.skinned_meshes())
def test_skin_blend_matches_numpy_lbs(mesh):
    rest, joints, weights, bones = mesh
    affines = np.stack([call(K.versor_to_affine, b.versor()) for b in bones])
    out, out_par = np.empty_like(rest), np.empty_like(rest)
    SK.skin_blend(rest, joints, weights, affines, out)
    SK.skin_blend_parallel(rest, joints, weights, affines, out_par)
    np.testing.assert_array_equal(out, out_par)
    mag = max(1.0, max(b.magnitude for b in bones) * max(1.0, float(np.abs(rest).max())))
    assert record("skin_blend", rel_err(out, _numpy_lbs(rest, joints, weights, affines), mag)) <= TOL.kernel
    # and against matrix LBS of the same similarities (no versor on that side)
    mats = np.stack([b.matrix()[:3].ravel() for b in bones])
    assert record("skin_blend", rel_err(out, _numpy_lbs(rest, joints, weights, mats), mag)) <= TOL.large
