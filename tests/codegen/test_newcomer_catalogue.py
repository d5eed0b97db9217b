"""A catalogue written only from the README ("Write your own kernels"): it builds, verifies and runs.

Every kernel of ``tests/codegen/catalogues/newcomer.py`` is checked against plain-numpy Euclidean
formulas written here (projection, Householder reflection, sphere inversion, Plücker line of two
planes, Rodrigues rotation + translation), in its scalar and its ``_batch`` form, on hypothesis-drawn
inputs. Input layouts follow the README and the layouts the build writes into each docstring:
``cga.Plane`` (n, d) is the plane n·x = d, ``pga.Plane`` (a, b, c, d) is a x + b y + c z + d = 0,
``cga.Sphere`` is (c, (|c|² − r²)/2, 1) on (e1, e2, e3, e∞, e0), motors are T R with R = exp(−θ/2 I a).
"""
import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cgaskin import codegen, versor

CATALOGUE = Path(__file__).parent / "catalogues" / "newcomer.py"
SETTINGS = settings(max_examples=40, deadline=None, derandomize=True)


def _quiet(*args, **kwargs):
    pass


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("newcomer")
    assert codegen.build_catalogue(str(CATALOGUE), str(out), log=_quiet) == 0
    return out


VERIFY = """
import sys
from cgaskin import codegen
report = codegen.verify_catalogue(sys.argv[1], out=sys.argv[2], examples=10, rebuild=False,
                                  log=lambda *a, **k: None)
print(report.table())
print(" ".join(k.name for k in report.kernels))
sys.exit(0 if report.ok else report.failure_text() or 1)
"""


@pytest.fixture(scope="module")
def verifying(built):
    """`verify_catalogue(path, examples=10)` on the build, in its own process from the start: it spends
    ~20 s compiling clifford's and the kernels' numba code, which overlaps the oracle tests here."""
    log = open(built / "verify.log", "w+")
    proc = subprocess.Popen([sys.executable, "-c", VERIFY, str(CATALOGUE), str(built)],
                            stdout=log, stderr=subprocess.STDOUT, text=True)
    proc.log = log
    yield proc
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    log.close()


@pytest.fixture(scope="module")
def nc(built, verifying):
    path = built / "newcomer.py"
    name = "newcomer_generated_" + built.name
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    # numba's cache=True needs the module importable by name when a later process loads the cache
    sys.modules[name] = module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(name, None)


# ---------------------------------------------------------------- independent numpy oracles

def rodrigues(axis, angle, x):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    x = np.asarray(x, float)
    return (x * np.cos(angle) + np.cross(a, x) * np.sin(angle)
            + np.outer(x @ a, a).reshape(x.shape) * (1 - np.cos(angle)))


def motor_coefficients(axis, angle, t):
    """T R on (1, e12, e13, e23, e1∞, e2∞, e3∞, e123∞): R = cos θ/2 − sin θ/2 (a1 e23 − a2 e13 + a3 e12),
    T = 1 − t e∞ / 2, so V = R − (t R) e∞ / 2 (e∞ commutes with e12, e13, e23)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    c, s = np.cos(angle / 2), np.sin(angle / 2)
    r0, r12, r13, r23 = c, -s * a[2], s * a[1], -s * a[0]
    t1, t2, t3 = t
    v1 = r0 * t1 - t2 * r12 - t3 * r13
    v2 = r0 * t2 + t1 * r12 - t3 * r23
    v3 = r0 * t3 + t1 * r13 + t2 * r23
    v123 = t1 * r23 - t2 * r13 + t3 * r12
    return np.array([r0, r12, r13, r23, -v1 / 2, -v2 / 2, -v3 / 2, -v123 / 2])


def pga_motor_coefficients(axis, angle, t):
    """The same T R in PGA's order (1, e01, e02, e03, e12, e13, e23, e0123): e0 plays e∞'s part."""
    m = motor_coefficients(axis, angle, t)
    return m[[0, 4, 5, 6, 1, 2, 3, 7]]


def close(got, want, scale, rtol=1e-12):
    got, want = np.asarray(got, float), np.asarray(want, float)
    bound = rtol * max(1.0, scale, float(np.max(np.abs(want))))
    assert got.shape == want.shape
    assert np.max(np.abs(got - want)) <= bound, (got, want, np.max(np.abs(got - want)), bound)


# ---------------------------------------------------------------- strategies

coord = st.floats(-10, 10, allow_nan=False, allow_infinity=False)
vec3 = st.tuples(coord, coord, coord).map(np.array)
big = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
translation = st.tuples(big, big, big).map(np.array)
unit_ish = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 0.1).map(np.array)
angle = st.floats(-np.pi, np.pi)
weight = st.floats(0.25, 4.0)


@st.composite
def cga_planes(draw):
    """(n, d) with |n| anywhere in [0.1·w, √3·w]: the plane n·x = d."""
    n = draw(unit_ish) * draw(weight)
    return np.array([*n, draw(coord)])


@st.composite
def spheres(draw):
    """((c, (|c|² − r²)/2, 1) · w, c, r): any positive weight w gives the same inversion."""
    c, r, w = draw(vec3), draw(st.floats(0.5, 5)), draw(weight)
    return np.array([*c, (c @ c - r * r) / 2, 1.0]) * w, c, r


@st.composite
def rows(draw, element, n_max=6):
    return draw(st.lists(element, min_size=1, max_size=n_max))


# ---------------------------------------------------------------- build and verify

KERNELS = ("project_onto_plane", "invert_in_sphere", "meet_planes", "rigid_move", "plane_distance",
           "pga_reflect", "pga_compose", "pga_move")


def test_module_has_every_kernel_and_its_batch_form(nc):
    assert tuple(nc.KERNEL_NAMES) == KERNELS
    for name in KERNELS:
        assert callable(getattr(nc, name)) and callable(getattr(nc, name + "_batch"))
    for name in ("rigid_move", "pga_move"):                        # staged: uniform M, hoisting pays
        assert callable(getattr(nc, f"_{name}_uniform")) and callable(getattr(nc, f"_{name}_row"))


# ---------------------------------------------------------------- CGA kernels against numpy

def project_oracle(plane, x):
    n, d = plane[:3], plane[3]
    return x - (n @ x - d) * n / (n @ n)


@SETTINGS
@given(cga_planes(), vec3)
def test_project_onto_plane(nc, plane, x):
    want = project_oracle(plane, x)
    close(nc.project_onto_plane(plane, x), want, 10)
    assert abs(plane[:3] @ want - plane[3]) <= 1e-12 * 10 * np.linalg.norm(plane[:3])


@SETTINGS
@given(rows(st.tuples(cga_planes(), vec3)))
def test_project_onto_plane_batch(nc, pairs):
    planes, xs = np.array([p for p, _ in pairs]), np.array([x for _, x in pairs])
    out = np.empty((len(pairs), 3))
    nc.project_onto_plane_batch(planes, xs, out)
    close(out, [project_oracle(p, x) for p, x in pairs], 10)


def invert_oracle(c, r, x):
    v = x - c
    return c + r * r * v / (v @ v)


away = lambda s_x: np.linalg.norm(s_x[1] - s_x[0][1]) >= 0.5      # keep |x − c| ≥ 0.5


@SETTINGS
@given(st.tuples(spheres(), vec3).filter(away))
def test_invert_in_sphere(nc, sphere_x):
    (S, c, r), x = sphere_x
    want = invert_oracle(c, r, x)
    close(nc.invert_in_sphere(S, x), want, 10)
    if np.linalg.norm(x - c) <= 2 * r:       # an involution (well conditioned only near the sphere)
        close(nc.invert_in_sphere(S, np.asarray(nc.invert_in_sphere(S, x))), x, 10, rtol=1e-11)
    # the sphere itself stays put
    on = c + r * (x - c) / np.linalg.norm(x - c)
    close(nc.invert_in_sphere(S, on), on, 10)


@SETTINGS
@given(rows(st.tuples(spheres(), vec3).filter(away)))
def test_invert_in_sphere_batch(nc, items):
    S = np.array([s[0] for s, _ in items])
    xs = np.array([x for _, x in items])
    out = np.empty((len(items), 3))
    nc.invert_in_sphere_batch(S, xs, out)
    close(out, [invert_oracle(s[1], s[2], x) for s, x in items], 10)


def meet_oracle(p, q):
    """(u3, −u2, u1, m): the direction u = n_p × n_q as a bivector on (e12, e13, e23), and the Plücker
    moment m = x0 × u on (e1∞, e2∞, e3∞), x0 = (d_p n_q × u + d_q u × n_p) / |u|² the line's point
    nearest the origin (on both planes)."""
    n1, n2, d1, d2 = p[:3], q[:3], p[3], q[3]
    u = np.cross(n1, n2)
    x0 = (d1 * np.cross(n2, u) + d2 * np.cross(u, n1)) / (u @ u)
    assert np.allclose([n1 @ x0, n2 @ x0], [d1, d2], rtol=1e-9, atol=1e-9)
    return np.array([u[2], -u[1], u[0], *np.cross(x0, u)])


not_parallel = lambda pq: (np.linalg.norm(np.cross(pq[0][:3], pq[1][:3]))
                           >= 0.2 * np.linalg.norm(pq[0][:3]) * np.linalg.norm(pq[1][:3]))


@SETTINGS
@given(st.tuples(cga_planes(), cga_planes()).filter(not_parallel))
def test_meet_planes(nc, pq):
    p, q = pq
    close(nc.meet_planes(p, q), meet_oracle(p, q), 10)


@SETTINGS
@given(rows(st.tuples(cga_planes(), cga_planes()).filter(not_parallel)))
def test_meet_planes_batch(nc, pairs):
    P, Q = np.array([p for p, _ in pairs]), np.array([q for _, q in pairs])
    out = np.empty((len(pairs), 6))
    nc.meet_planes_batch(P, Q, out)
    close(out, [meet_oracle(p, q) for p, q in pairs], 10)


@SETTINGS
@given(unit_ish, angle, translation, vec3)
def test_rigid_move(nc, axis, th, t, x):
    M = motor_coefficients(axis, th, t)
    close(nc.rigid_move(M, x), rodrigues(axis, th, x) + t, 1e3)


@SETTINGS
@given(unit_ish, angle, translation, rows(vec3, 8))
def test_rigid_move_batch_uniform_motor(nc, axis, th, t, xs):
    M, xs = motor_coefficients(axis, th, t), np.array(xs)
    out = np.empty((len(xs), 3))
    nc.rigid_move_batch(M, xs, out)                        # M once, xs (N, 3)
    close(out, rodrigues(axis, th, xs) + t, 1e3)


@SETTINGS
@given(unit_ish, angle, translation)
def test_rigid_move_with_versor_motor(nc, axis, th, t):
    """The README's `versor.motor` (its first 8 coefficients) moves points the same way."""
    V = np.asarray(versor.motor(axis, th, t), float)
    assert V.shape == (12,) and not V[8:].any()
    M = V[:8]
    close(M, motor_coefficients(axis, th, t), 1e3)
    x = np.array([1.0, -2.0, 3.0])
    close(nc.rigid_move(M, x), rodrigues(axis, th, x) + t, 1e3)


def distance_oracle(plane, x):
    n, d = plane[:3], plane[3]
    return abs(n @ x - d) / np.linalg.norm(n)


@SETTINGS
@given(cga_planes(), vec3)
def test_plane_distance(nc, plane, x):
    got = nc.plane_distance(plane, x)
    assert isinstance(got, float)
    close(got, distance_oracle(plane, x), 10)
    close(nc.plane_distance(plane, project_oracle(plane, x)), 0.0, 10)


@SETTINGS
@given(rows(st.tuples(cga_planes(), vec3)))
def test_plane_distance_batch(nc, pairs):
    planes, xs = np.array([p for p, _ in pairs]), np.array([x for _, x in pairs])
    out = np.empty((len(pairs), 1))
    nc.plane_distance_batch(planes, xs, out)
    close(out[:, 0], [distance_oracle(p, x) for p, x in pairs], 10)


# ---------------------------------------------------------------- PGA kernels against numpy

def pga_reflect_oracle(plane, x):
    """Householder reflection in a x + b y + c z + d = 0."""
    n, d = plane[:3], plane[3]
    return x - 2 * (n @ x + d) * n / (n @ n)


@SETTINGS
@given(cga_planes(), vec3)
def test_pga_reflect(nc, plane, x):
    close(nc.pga_reflect(plane, x), pga_reflect_oracle(plane, x), 10)


@SETTINGS
@given(rows(st.tuples(cga_planes(), vec3)))
def test_pga_reflect_batch(nc, pairs):
    planes, xs = np.array([p for p, _ in pairs]), np.array([x for _, x in pairs])
    out = np.empty((len(pairs), 3))
    nc.pga_reflect_batch(planes, xs, out)
    close(out, [pga_reflect_oracle(p, x) for p, x in pairs], 10)


motion = st.tuples(unit_ish, angle, translation)


def moved(a, x):
    """Rodrigues rotation about the axis through the origin, then the translation."""
    return rodrigues(a[0], a[1], x) + a[2]


@SETTINGS
@given(motion, vec3)
def test_pga_move(nc, a, x):
    close(nc.pga_move(pga_motor_coefficients(*a), x), moved(a, x), 1e3)


@SETTINGS
@given(motion, rows(vec3, 8))
def test_pga_move_batch_uniform_motor(nc, a, xs):
    xs = np.array(xs)
    out = np.empty((len(xs), 3))
    nc.pga_move_batch(pga_motor_coefficients(*a), xs, out)          # M once, xs (N, 3)
    close(out, moved(a, xs), 1e3)


def rotor_part_is_unit(M):
    """M ~M = 1 for a unit motor: |rotor|² = 1 and the e0123 part of M ~M vanishes."""
    s, e01, e02, e03, e12, e13, e23, e0123 = M
    return (abs(s * s + e12 * e12 + e13 * e13 + e23 * e23 - 1) <= 1e-13
            and abs(s * e0123 - e01 * e23 + e02 * e13 - e03 * e12) <= 1e-12 * max(1, np.max(np.abs(M))))


@SETTINGS
@given(motion, motion, vec3)
def test_pga_compose_moves_by_b_then_a(nc, a, b, x):
    AB = np.array(nc.pga_compose(pga_motor_coefficients(*a), pga_motor_coefficients(*b)))
    assert AB.shape == (8,) and rotor_part_is_unit(AB)
    close(nc.pga_move(AB, x), moved(a, moved(b, x)), 2e3)


@SETTINGS
@given(rows(st.tuples(motion, motion)), vec3)
def test_pga_compose_batch(nc, pairs, x):
    A = np.array([pga_motor_coefficients(*a) for a, _ in pairs])
    B = np.array([pga_motor_coefficients(*b) for _, b in pairs])
    out = np.empty((len(pairs), 8))
    nc.pga_compose_batch(A, B, out)                        # no uniform input: A and B are (N, 8)
    for AB, (a, b) in zip(out, pairs):
        close(AB, nc.pga_compose(pga_motor_coefficients(*a), pga_motor_coefficients(*b)), 1e3, rtol=0)
        close(nc.pga_move(AB, x), moved(a, moved(b, x)), 2e3)


# ---------------------------------------------------------------- verify (last: it ran meanwhile)

def test_catalogue_verifies(verifying):
    verifying.wait(timeout=300)
    verifying.log.seek(0)
    output = verifying.log.read()
    assert verifying.returncode == 0, output
    assert output.strip().splitlines()[-1].split() == list(KERNELS), output
