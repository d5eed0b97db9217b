"""Hypothesis strategies for the kernel and versor property tests.

Geometric inputs come as plain parameters (axis, angle, translation, scale) wrapped in ``Similarity``
so that each test can build the same transformation three independent ways: with cgaskin
(``.versor()``), as a float64 matrix (``.matrix()``, Rodrigues + s + t) and, in the clifford tests,
with clifford's own multivectors.

Ranges (design.md section 6): translations and points up to 1e4 (``TOL.large_coordinate``; moderate
ones up to 10 for clifford), scales log-uniform in [0.01, 100], angles in [-2 pi, 2 pi] with exactly 0,
+-pi, +-2 pi and tiny angles.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from hypothesis import strategies as st

from .tolerances import TOL

TAU = 2.0 * math.pi
SPECIAL_ANGLES = (0.0, math.pi, -math.pi, TAU, -TAU, 0.5 * math.pi, -0.5 * math.pi, 1e-9, -1e-9,
                  1e-12, math.pi - 1e-9)
COORDINATE_AXES = tuple(tuple(float(s) * np.eye(3)[i]) for i in range(3) for s in (1, -1))


def finite(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def vec3(lo: float, hi: float) -> st.SearchStrategy[np.ndarray]:
    return st.tuples(finite(lo, hi), finite(lo, hi), finite(lo, hi)).map(np.array)


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    """Log-uniform in [lo, hi] (both > 0), endpoints included."""
    return st.one_of(st.sampled_from((lo, hi)),
                     finite(math.log(lo), math.log(hi)).map(lambda v: min(max(math.exp(v), lo), hi)))


# ---- elementary parameters ---------------------------------------------------------------------------
def unit_axes() -> st.SearchStrategy[np.ndarray]:
    """Unit 3-vectors: the coordinate axes (both signs), nearly-axis vectors, and general directions."""
    general = vec3(-1.0, 1.0).filter(lambda v: np.linalg.norm(v) > 0.1).map(lambda v: v / np.linalg.norm(v))
    near_axis = st.tuples(st.sampled_from(COORDINATE_AXES), vec3(-1e-9, 1e-9)).map(
        lambda p: (np.array(p[0]) + p[1]) / np.linalg.norm(np.array(p[0]) + p[1]))
    return st.one_of(st.sampled_from(COORDINATE_AXES).map(np.array), near_axis, general, general)


def angles(lo: float = -TAU, hi: float = TAU) -> st.SearchStrategy[float]:
    """Angles in [lo, hi] radians, with the special values that fall inside the range."""
    special = tuple(a for a in SPECIAL_ANGLES if lo <= a <= hi)
    return st.one_of(st.sampled_from(special), finite(lo, hi), finite(lo, hi))


def translations(max_abs: float = TOL.large_coordinate) -> st.SearchStrategy[np.ndarray]:
    """(3,) vectors with components in [-max_abs, max_abs]: zero, uniform, and log-spread magnitudes."""
    spread = st.tuples(unit_axes(), log_uniform(1e-6, 1.0)).map(lambda p: p[0] * p[1] * max_abs)
    return st.one_of(st.just(np.zeros(3)), vec3(-max_abs, max_abs), spread)


def scales(lo: float = TOL.scale_min, hi: float = TOL.scale_max) -> st.SearchStrategy[float]:
    """Uniform scale factors, log-uniform in [lo, hi], 1 included."""
    return st.one_of(st.just(1.0), log_uniform(lo, hi))


def points(max_abs: float = TOL.large_coordinate) -> st.SearchStrategy[np.ndarray]:
    """(3,) points with components up to ``max_abs`` (zero and log-spread magnitudes included)."""
    return translations(max_abs)


def moderate_points() -> st.SearchStrategy[np.ndarray]:
    """Points with |components| <= 10: where clifford's up/down are exact to ~1e-14."""
    return points(TOL.moderate)


# ---- similarities: rotors, translators, dilators, motors, versors -------------------------------------
@dataclass(frozen=True, eq=False)
class Similarity:
    """x -> scale * R(axis, angle) x + translation, i.e. the versor T(translation) R(axis, angle) D(scale)."""

    axis: np.ndarray
    angle: float
    translation: np.ndarray
    scale: float

    def rotation_matrix(self) -> np.ndarray:
        return rotation_matrix(self.axis, self.angle)

    def linear(self) -> np.ndarray:
        return self.scale * self.rotation_matrix()

    def matrix(self) -> np.ndarray:
        m = np.eye(4)
        m[:3, :3] = self.linear()
        m[:3, 3] = self.translation
        return m

    def apply(self, x) -> np.ndarray:
        return np.asarray(x, float) @ self.linear().T + self.translation

    def versor(self) -> np.ndarray:
        from cgaskin import versor as V
        return V.compose(V.translator(self.translation), V.rotor(self.axis, self.angle), V.dilator(self.scale))

    @property
    def magnitude(self) -> float:
        """The coordinate scale of the map's output at unit input: max(scale, |translation|_inf)."""
        return max(self.scale, float(np.max(np.abs(self.translation))))

    def __repr__(self):
        return (f"Similarity(axis={self.axis.tolist()!r}, angle={self.angle!r}, "
                f"translation={self.translation.tolist()!r}, scale={self.scale!r})")


def rotation_matrix(axis, angle) -> np.ndarray:
    """Rodrigues: right-handed rotation by ``angle`` about the unit vector ``axis``."""
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def similarities(max_translation: float = TOL.large_coordinate, rotation: bool = True,
                 translation: bool = True, scale: bool = True,
                 angle_range: tuple[float, float] = (-TAU, TAU)) -> st.SearchStrategy[Similarity]:
    zero = st.just(np.zeros(3))
    return st.builds(
        Similarity,
        axis=unit_axes(),
        angle=angles(*angle_range) if rotation else st.just(0.0),
        translation=translations(max_translation) if translation else zero,
        scale=scales() if scale else st.just(1.0),
    )


def rotors(**kw) -> st.SearchStrategy[Similarity]:
    return similarities(translation=False, scale=False, **kw)


def translators(max_translation: float = TOL.large_coordinate) -> st.SearchStrategy[Similarity]:
    return similarities(max_translation, rotation=False, scale=False)


def dilators() -> st.SearchStrategy[Similarity]:
    return similarities(rotation=False, translation=False)


def motors(max_translation: float = TOL.large_coordinate, **kw) -> st.SearchStrategy[Similarity]:
    return similarities(max_translation, scale=False, **kw)


def versors(max_translation: float = TOL.large_coordinate, **kw) -> st.SearchStrategy[Similarity]:
    """T R D with every factor drawn (identity factors included)."""
    return similarities(max_translation, **kw)


def moderate_versors(**kw) -> st.SearchStrategy[Similarity]:
    return similarities(TOL.moderate, **kw)


def coefficient_arrays(size: int = 12, max_abs: float = 10.0) -> st.SearchStrategy[np.ndarray]:
    """Arbitrary (size,) coefficient arrays (multivectors of a fixed blade set, not versors in general)."""
    return st.lists(finite(-max_abs, max_abs), min_size=size, max_size=size).map(np.array)


def _is_far_from_versor(v: np.ndarray) -> bool:
    """V V~ is not a positive scalar, by a margin far beyond rounding (~EPS |V|^2) and beyond the API's
    threshold (cgaskin.versor.VERSOR_TOLERANCE relative to |V|^2; note <V V~>_0 <= |V|^2)."""
    from cgaskin.generated.kernels import versor_residual
    residual, norm = versor_residual(v)
    return norm <= 0 or residual > TOL.non_versor_residual * max(float(np.sum(v * v)), 1.0)


def non_versors() -> st.SearchStrategy[np.ndarray]:
    """(12,) arrays that are not similarity versors (V V~ not a positive scalar): random arrays, the
    zero array, pure e-infinity-0 parts, and true versors with one coefficient pushed off."""
    def perturb(args):
        sim, index, delta = args
        v = sim.versor().copy()
        v[index] += delta
        return v
    structured = st.one_of(
        st.just(np.zeros(12)),
        st.tuples(finite(0.5, 5.0)).map(lambda a: np.r_[np.zeros(8), a[0], 0.0, 0.0, 0.0]),
        st.tuples(versors(TOL.moderate), st.integers(0, 11), st.sampled_from((-3.0, 2.0, 7.5))).map(perturb),
    )
    return st.one_of(coefficient_arrays(), structured).filter(_is_far_from_versor)


# ---- planes, triangles, weights ------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Plane:
    """{x : normal . x = distance} with a unit normal; ``array`` is the dual plane n + d e-inf (4,)."""

    normal: np.ndarray
    distance: float

    @property
    def array(self) -> np.ndarray:
        return np.r_[self.normal, self.distance]

    def point_on(self, tangent_coords) -> np.ndarray:
        """A point of the plane: distance * n plus an in-plane offset with the given 2 coordinates."""
        n = self.normal
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        t1 = np.cross(n, helper)
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        return self.distance * n + tangent_coords[0] * t1 + tangent_coords[1] * t2


def planes(max_distance: float = TOL.large_coordinate) -> st.SearchStrategy[Plane]:
    distance = st.one_of(st.just(0.0), finite(-max_distance, max_distance))
    return st.builds(Plane, normal=unit_axes(), distance=distance)


def triangle_quality(a, b, c) -> float:
    """|(b-a) x (c-a)| / (longest edge)^2: 0 for degenerate triangles, sqrt(3)/2 for equilateral ones."""
    u, w = np.subtract(b, a), np.subtract(c, a)
    longest = max(u @ u, w @ w, (w - u) @ (w - u))
    return float(np.linalg.norm(np.cross(u, w)) / longest) if longest > 0 else 0.0


def triangles(max_abs: float = TOL.large_coordinate, min_size: float = 1e-2,
              min_quality: float = 0.05) -> st.SearchStrategy[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Non-degenerate triangles (a, b, c): corner a anywhere within ``max_abs``, edges a->b and a->c of
    length between size / 4 and size, size log-spread in [``min_size``, ``max_abs``], quality (twice
    the area over the squared longest edge) at least ``min_quality``."""
    def build(args):
        a, size, u, lu, w, lw = args
        return a, a + size * lu * u, a + size * lw * w
    length = finite(0.25, 1.0)
    tri = st.tuples(points(max_abs), log_uniform(min_size, max_abs), unit_axes(), length, unit_axes(), length)
    return tri.map(build).filter(lambda t: triangle_quality(*t) >= min_quality)


def weights(k: int) -> st.SearchStrategy[np.ndarray]:
    """k non-negative weights summing to 1 (one-hot rows included)."""
    one_hot = st.integers(0, k - 1).map(lambda i: np.eye(k)[i])
    general = st.lists(finite(0.0, 1.0), min_size=k, max_size=k).filter(lambda w: sum(w) > 1e-3).map(
        lambda w: np.asarray(w) / np.sum(w))
    return st.one_of(one_hot, general, general)


@st.composite
def skinned_meshes(draw, max_vertices: int = 40, max_bones: int = 6, max_influences: int = 4,
                   max_abs: float = TOL.large_coordinate):
    """(rest (n,3), joints (n,k) int64, weights (n,k) rows summing to 1, bones [Similarity])."""
    n = draw(st.integers(1, max_vertices))
    n_bones = draw(st.integers(1, max_bones))
    k = draw(st.integers(1, max_influences))
    seed = draw(st.integers(0, 2 ** 32 - 1))
    bones = draw(st.lists(versors(max_abs), min_size=n_bones, max_size=n_bones))
    rng = np.random.default_rng(seed)
    rest = rng.uniform(-max_abs, max_abs, (n, 3)) * draw(log_uniform(1e-3, 1.0))
    joints = rng.integers(0, n_bones, (n, k))
    w = rng.uniform(0.0, 1.0, (n, k)) ** 2
    w[np.arange(n), rng.integers(0, k, n)] += 1e-3          # no all-zero rows
    w /= w.sum(axis=1, keepdims=True)
    return rest, joints.astype(np.int64), w, bones
