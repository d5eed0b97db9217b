"""Another algebra end to end: kernels in PGA G(3,0,1) (``cgaskin.codegen.pga``) build, verify against
clifford's Cl(3,0,1), and move, reflect and compose points as plain matrices do."""
import importlib.util
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cgaskin.codegen import build_catalogue, verify_catalogue
from cgaskin.codegen.ir import CodegenError

from tests.helpers.catalogues import PGA_CATALOGUE


@pytest.fixture(scope="module")
def pga_module(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pga")
    (folder / "pgakernels.py").write_text(PGA_CATALOGUE, encoding="utf-8")
    build_catalogue(folder / "pgakernels.py", folder / "out", log=lambda *_: None)
    spec = importlib.util.spec_from_file_location("pgakernels_built", folder / "out" / "pgakernels.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return folder, module


def _rotation(axis, angle):
    """Rodrigues' rotation matrix (right-handed about the unit ``axis``)."""
    n = axis / np.linalg.norm(axis)
    k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _motor(module, axis, angle, t):
    """T(t) R(axis, angle) on (s, e01, e02, e03, e12, e13, e23, e0123), by the documented conventions."""
    n = axis / np.linalg.norm(axis)
    c, s = np.cos(angle / 2), np.sin(angle / 2)
    rotor = np.array([c, 0, 0, 0, -s * n[2], s * n[1], -s * n[0], 0])
    translator = np.array([1.0, -t[0] / 2, -t[1] / 2, -t[2] / 2, 0, 0, 0, 0])
    return np.array(module.compose(translator, rotor))


def test_the_pga_catalogue_verifies_against_clifford(pga_module):
    folder, _ = pga_module
    report = verify_catalogue(folder / "pgakernels.py", examples=10)
    assert [k.name for k in report.kernels] == ["move", "reflect", "meet", "compose"]
    assert all(k.err_clifford < 1e-12 and k.err_expansion < 1e-12 for k in report.kernels), report.table()


def test_the_motor_sandwich_is_hoisted_into_an_affine_map(pga_module):
    _, module = pga_module
    assert "Batch form per row: " in module.move.__doc__ and "(12 hoisted values)" in module.move.__doc__
    assert "algebra: G(3,0,1)" in module.__doc__


vectors = st.tuples(*[st.floats(-1e3, 1e3, allow_nan=False)] * 3).map(np.array)


@settings(max_examples=40, deadline=None)
@given(axis=vectors.filter(lambda v: np.linalg.norm(v) > 1e-3), angle=st.floats(0, np.pi), t=vectors,
       points=st.lists(vectors, min_size=1, max_size=5))
def test_a_motor_moves_points_as_rotation_then_translation(pga_module, axis, angle, t, points):
    _, module = pga_module
    M = _motor(module, axis, angle, t)
    x = np.array(points)
    want = x @ _rotation(axis, angle).T + t
    out = np.empty_like(x)
    module.move_batch(M, x, out)
    scale = 1 + np.abs(x).max() + np.abs(t).max()
    np.testing.assert_allclose(out, want, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(module.move(M, x[0]), want[0], rtol=0, atol=1e-12 * scale)


@settings(max_examples=40, deadline=None)
@given(normal=vectors.filter(lambda v: np.linalg.norm(v) > 1e-3), d=st.floats(-1e3, 1e3), x=vectors)
def test_reflection_in_a_plane_matches_householder(pga_module, normal, d, x):
    _, module = pga_module
    n = normal / np.linalg.norm(normal)
    got = np.array(module.reflect(np.append(n, d), x))     # the plane n·x + d = 0
    want = x - 2 * (n @ x + d) * n
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * (1 + np.abs(x).max() + abs(d)))


def test_the_meet_of_two_planes_is_their_line(pga_module):
    _, module = pga_module
    # z = 0 and y = 0 meet in the x axis: the line's Euclidean part (e12, e13, e23) is along e23's dual
    line = np.array(module.meet(np.array([0, 0, 1.0, 0]), np.array([0, 1.0, 0, 0])))
    assert np.count_nonzero(line) == 1 and line[5] != 0        # only e23: the direction e1


def test_mixing_algebras_and_dual_in_a_degenerate_metric_are_clear_errors(tmp_path):
    mixed = tmp_path / "mixed.py"
    mixed.write_text(textwrap.dedent('''
        from cgaskin.codegen import cga, kernel, pga

        @kernel
        def mixed(p: pga.Plane, x: cga.Point) -> pga.Plane:
            return p * x
    '''), encoding="utf-8")
    with pytest.raises(CodegenError, match="one kernel, one algebra"):
        build_catalogue(mixed, tmp_path / "out", log=lambda *_: None)
    dual = tmp_path / "dual.py"
    dual.write_text(textwrap.dedent('''
        from cgaskin.codegen import kernel, pga

        @kernel
        def dual(p: pga.Plane) -> pga.Point:
            return p.dual()
    '''), encoding="utf-8")
    with pytest.raises(CodegenError, match="degenerate"):
        build_catalogue(dual, tmp_path / "out", log=lambda *_: None)
