"""cgaskin.algebra.transforms against the independent reference implementations in cgaskin.baselines.

The two sides share no code and no formula: quaternion -> matrix is written out entry by entry in
transforms and is the Rodrigues form I + 2 w [v]x + 2 [v]x^2 in baselines; matrix -> quaternion is
Shepperd's method against the eigenvector of Bar-Itzhack's 4x4 matrix; T @ R @ S fills the blocks
against a product of three matrices. Rotation matrices are built by the tests' own Rodrigues formula
(axis, angle), half turns included. Both implementations must agree to TOL.kernel (1e-12) relative.
"""
import numpy as np
from hypothesis import given, strategies as st

from cgaskin import baselines as B
from cgaskin.algebra import transforms as T
from tests.helpers import strategies as S
from tests.helpers.tolerances import TOL, rel_err


def unit_quaternion(axis, angle) -> np.ndarray:
    return np.r_[np.sin(angle / 2) * axis, np.cos(angle / 2)]


def quaternions() -> st.SearchStrategy[np.ndarray]:
    """(4,) quaternions of any non-negligible length (both sides normalise): unit ones from an axis and
    an angle (special angles included), the same scaled by 1e-3 .. 1e3, and raw component draws."""
    unit = st.tuples(S.unit_axes(), S.angles()).map(lambda p: unit_quaternion(*p))
    scaled = st.tuples(unit, S.log_uniform(1e-3, 1e3)).map(lambda p: p[0] * p[1])
    raw = st.tuples(*[S.finite(-1.0, 1.0)] * 4).map(np.array).filter(lambda q: np.linalg.norm(q) > 1e-3)
    return st.one_of(unit, scaled, raw)


def signed_scales() -> st.SearchStrategy[np.ndarray]:
    """(3,) per-axis scales, 0.01 .. 100 in size, either sign (mirrors)."""
    signed = st.tuples(S.scales(), st.sampled_from([1.0, -1.0])).map(lambda p: p[0] * p[1])
    return st.tuples(signed, signed, signed).map(np.array)


def sign_free_err(q1, q2) -> float:
    """Largest component difference of two unit quaternions, up to the overall sign (q and -q are
    the same rotation; at a half turn w = 0 and each side picks a sign of its own)."""
    return min(rel_err(q1, q2, 1.0), rel_err(q1, -np.asarray(q2), 1.0))


@given(quaternions())
def test_quat_to_matrix_agrees(q):
    assert rel_err(B.quat_to_matrix(q), T.quat_to_matrix(q), 1.0) <= TOL.kernel


@given(S.unit_axes(), S.angles(), S.translations())
def test_matrix_to_quat_agrees(axis, angle, translation):
    r = S.rotation_matrix(axis, angle)
    m4 = np.eye(4)
    m4[:3, :3], m4[:3, 3] = r, translation                       # 4x4 input: the 3x3 block is read
    expected = unit_quaternion(axis, angle)
    for m in (r, m4):
        got_b, got_t = B.matrix_to_quat(m), T.matrix_to_quat(m)
        assert got_b[3] >= 0 and got_t[3] >= 0
        assert abs(np.linalg.norm(got_b) - 1) <= TOL.kernel and abs(np.linalg.norm(got_t) - 1) <= TOL.kernel
        assert sign_free_err(got_b, got_t) <= TOL.kernel
        assert sign_free_err(got_b, expected) <= TOL.kernel       # and both are the rotation's quaternion
        if got_t[3] > TOL.kernel:                                 # away from half turns: the same sign too
            assert rel_err(got_b, got_t, 1.0) <= TOL.kernel


@given(st.lists(st.tuples(S.unit_axes(), S.angles()), min_size=1, max_size=6))
def test_batched_matrix_to_quat_and_back_agree(rotations):
    r = np.stack([S.rotation_matrix(axis, angle) for axis, angle in rotations]).reshape(-1, 1, 3, 3)
    got_b, got_t = B.matrix_to_quat(r), T.matrix_to_quat(r)
    assert got_b.shape == got_t.shape == (len(rotations), 1, 4)
    for qb, qt in zip(got_b.reshape(-1, 4), got_t.reshape(-1, 4)):
        assert sign_free_err(qb, qt) <= TOL.kernel
    back_b, back_t = B.quat_to_matrix(got_b), T.quat_to_matrix(got_t)
    assert back_b.shape == back_t.shape == r.shape
    assert rel_err(back_b, back_t, 1.0) <= TOL.kernel and rel_err(back_b, r, 1.0) <= TOL.kernel


@given(S.translations(), quaternions(), signed_scales())
def test_trs_matrix_agrees(t, q, s):
    magnitude = max(1.0, float(np.abs(t).max()), float(np.abs(s).max()))
    assert rel_err(B.trs_matrix(t, q, s), T.trs_matrix(t, q, s), magnitude) <= TOL.kernel


@given(st.lists(st.tuples(S.translations(), quaternions()), min_size=1, max_size=5), signed_scales())
def test_trs_matrix_broadcasts_alike(pairs, s):
    t = np.stack([p[0] for p in pairs])
    q = np.stack([p[1] for p in pairs])[:, None]                  # (n, 1, 4) against t (n, 3): (n, n)
    got_b, got_t = B.trs_matrix(t, q, s), T.trs_matrix(t, q, s)
    assert got_b.shape == got_t.shape == (len(pairs), len(pairs), 4, 4)
    magnitude = max(1.0, float(np.abs(t).max()), float(np.abs(s).max()))
    assert rel_err(got_b, got_t, magnitude) <= TOL.kernel
