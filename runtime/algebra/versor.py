"""Versors of CGA as float64 arrays: rotation, translation and uniform scale in one algebra.

A versor is an array of shape (..., 12): its coefficients on ``VERSOR_BLADES``
(1, e12, e13, e23, e1∞, e2∞, e3∞, e123∞, e∞0, e12∞0, e13∞0, e23∞0) in the null basis
(e∞ = e− + e+, e0 = (e− − e+)/2). Every function is batched over leading axes and calls only the
generated kernels. ``compose(a, b)`` applies b first (like matrices); a joint's local transform is
T R D.
"""
from __future__ import annotations

import numpy as np

from .._shared.checks import float_array
from .._shared.jit import F2, F1r, F2r, precompiled
from ..errors import InvalidInputError
from ..generated import kernels as K
from ..generated.layout import LOG_BLADES, LOG_SIZE, VERSOR_BLADES, VERSOR_SIZE
from ..tolerances import tol

__all__ = ["VERSOR_BLADES", "LOG_BLADES", "identity", "translator", "rotor", "rotor_from_quaternion",
           "dilator", "motor", "compose", "reverse", "inverse", "normalise", "apply", "to_matrix",
           "to_affine", "from_matrix", "log", "exp", "blend_linear", "blend_log", "to_clifford",
           "from_clifford", "is_versor"]

# the generated kernels these functions call, with the argument types ``_rows`` gives them
precompiled(K.versor_translator_batch, (F2r, F2), cost=0.3)
precompiled(K.versor_rotor_batch, (F2r, F1r, F2), cost=0.2)
precompiled(K.versor_rotor_quaternion_batch, (F2r, F2), cost=0.1)
precompiled(K.versor_dilator_batch, (F1r, F2), cost=0.3)
precompiled(K.gp_versor_versor_batch, (F2r, F2r, F2), cost=0.7)
precompiled(K.versor_to_affine_batch, (F2r, F2), cost=0.4)
precompiled(K.versor_residual_batch, (F2r, F2), cost=0.2)
precompiled(K.reverse_versor_batch, (F2r, F2), cost=0.2)
precompiled(K.versor_log_batch, (F2r, F2), cost=0.5)
precompiled(K.versor_exp_batch, (F2r, F2), cost=0.4)
# compiled inside the batch kernels above; listed so that one process owns each cache index
precompiled(K.reverse_versor, (F1r,), cost=0.2)
precompiled(K.versor_log, (F1r,), cost=0.4)
precompiled(K.versor_exp, (F1r,), cost=0.2)

#: dilation factors a versor holds: V Ṽ of a dilator cancels terms of the size of the scale, so
#: beyond about 1e15 (or below 1e-16) float64 cannot hold one at all; 1e±12 keeps a margin
SCALE_RANGE = (1e-12, 1e12)
VERSOR_TOLERANCE = tol.versor        # relative residual of V Ṽ beyond which an array is not a versor


def _rows(kernel_batch, n_out, *arrays):
    """Run a generated ``_batch`` kernel over broadcast leading axes; returns (..., n_out)."""
    shapes = [a.shape[:-1] if is_vector else a.shape for a, is_vector in arrays]
    try:
        lead = np.broadcast_shapes(*shapes)
    except ValueError:
        raise InvalidInputError(f"the arguments' leading axes {shapes} do not broadcast together") from None
    flat = []
    for a, is_vector in arrays:
        if is_vector:
            a = np.ascontiguousarray(np.broadcast_to(a, lead + a.shape[-1:])).reshape(-1, a.shape[-1])
        else:
            a = np.ascontiguousarray(np.broadcast_to(a, lead)).reshape(-1)
        # read-only views always (broadcasting gives some, copies not): one compiled kernel per type
        a = a.view()
        a.flags.writeable = False
        flat.append(a)
    n = int(np.prod(lead, dtype=np.int64))
    out = np.empty((n, n_out))
    if n:
        kernel_batch(*flat, out)
    return out.reshape(lead + (n_out,))


def _versor_test(arr):
    """(residual, scalar, ok): V Ṽ must be a positive scalar. Rounding alone leaves a non-scalar
    part of ~ε|V|² (large coefficients, e.g. translations of 1e4), so the residual is measured
    against the coefficients' squared size, not against ⟨V Ṽ⟩₀."""
    residual, norm = np.moveaxis(_rows(K.versor_residual_batch, 2, (arr, True)), -1, 0)
    size = np.sum(arr * arr, axis=-1)
    return residual, norm, (norm > 0) & (residual <= VERSOR_TOLERANCE * np.maximum(size, 1.0))


def _versor_arg(v, name="versor", check=True) -> np.ndarray:
    arr = float_array(v, name, last=VERSOR_SIZE)
    if check:
        residual, norm, ok = _versor_test(arr)
        bad = ~ok
        if np.any(bad):
            idx = tuple(np.argwhere(np.atleast_1d(bad))[0])
            raise InvalidInputError(
                f"{name} is not a similarity versor (V Ṽ must be a positive scalar; at index {idx} its "
                f"non-scalar part is {np.atleast_1d(residual)[idx]:.3g} against scalar "
                f"{np.atleast_1d(norm)[idx]:.3g}); build versors with motor/dilator/compose or "
                f"call normalise")
    return arr


def is_versor(v) -> np.ndarray:
    """(...,) bool: whether each (..., 12) array is a similarity versor (within tolerance)."""
    return _versor_test(float_array(v, "versor", last=VERSOR_SIZE))[2]


# ---- construction --------------------------------------------------------------------------------
def identity(shape=()) -> np.ndarray:
    v = np.zeros(tuple(np.atleast_1d(shape)) + (VERSOR_SIZE,) if shape != () else (VERSOR_SIZE,))
    v[..., 0] = 1.0
    return v


def translator(translation) -> np.ndarray:
    """T = 1 − ½ t e∞ for t : (..., 3)."""
    return _rows(K.versor_translator_batch, VERSOR_SIZE, (float_array(translation, "translation", 3), True))


def rotor(axis, angle) -> np.ndarray:
    """Rotation by ``angle`` radians about ``axis`` (..., 3) (right-handed, any nonzero length)."""
    axis = float_array(axis, "axis", 3)
    angle = float_array(angle, "angle")
    if np.any(np.linalg.norm(axis, axis=-1) == 0):
        raise InvalidInputError("axis has zero length: a rotation needs a direction")
    return _rows(K.versor_rotor_batch, VERSOR_SIZE, (axis, True), (angle, False))


def rotor_from_quaternion(q) -> np.ndarray:
    """Rotor of unit quaternions q : (..., 4) in (x, y, z, w) order (glTF's)."""
    q = float_array(q, "quaternion", 4)
    if np.any(np.linalg.norm(q, axis=-1) == 0):
        raise InvalidInputError("quaternion has zero length")
    return _rows(K.versor_rotor_quaternion_batch, VERSOR_SIZE, (q, True))


def dilator(scale) -> np.ndarray:
    """Uniform scale by ``scale`` > 0 about the origin: apply(dilator(s), x) == s * x."""
    scale = float_array(scale, "scale")
    low, high = SCALE_RANGE
    outside = (scale < low) | (scale > high)
    if np.any(outside):
        raise InvalidInputError(f"scale must lie in [{low:g}, {high:g}] (a dilation float64 can hold), "
                                f"got {float(scale[outside].flat[0])!r}")
    return _rows(K.versor_dilator_batch, VERSOR_SIZE, (scale, False))


def motor(axis=(0.0, 0.0, 1.0), angle=0.0, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rigid motion T(translation) R(axis, angle): rotate about the origin, then translate."""
    return compose(translator(translation), rotor(axis, angle))


# ---- algebra -------------------------------------------------------------------------------------
def compose(*versors) -> np.ndarray:
    """Geometric product V1 V2 ... Vn: applies Vn first, V1 last."""
    if not versors:
        raise InvalidInputError("compose needs at least one versor")
    result = np.array(_versor_arg(versors[0], "versors[0]", check=False))    # never the caller's array
    for i, v in enumerate(versors[1:], 1):
        result = _rows(K.gp_versor_versor_batch, VERSOR_SIZE, (result, True),
                       (_versor_arg(v, f"versors[{i}]", check=False), True))
    return result


def reverse(v) -> np.ndarray:
    return _rows(K.reverse_versor_batch, VERSOR_SIZE, (_versor_arg(v, check=False), True))


def inverse(v) -> np.ndarray:
    """V⁻¹ = Ṽ / (V Ṽ): undoes apply(V, ·)."""
    return _rows(K.inverse_versor_batch, VERSOR_SIZE, (_versor_arg(v), True))


def normalise(v) -> np.ndarray:
    """Nearest similarity versor T R D with V Ṽ = 1 (used after blending)."""
    arr = _versor_arg(v, check=False)
    rot = np.linalg.norm(arr[..., :4], axis=-1)
    dil = np.linalg.norm(arr[..., 8:], axis=-1)
    if np.any(rot <= dil):
        raise InvalidInputError("cannot normalise: the rotor part is not larger than the e∞0 part "
                                "(no positive scale matches); the input is not near a versor")
    return _rows(K.versor_normalise_batch, VERSOR_SIZE, (arr, True))


def to_affine(v) -> np.ndarray:
    """(..., 3, 4) affine maps [s R | t] with apply(V, x) = A[:, :3] x + A[:, 3]."""
    return _rows(K.versor_to_affine_batch, 12, (_versor_arg(v), True)).reshape(
        np.shape(v)[:-1] + (3, 4))


def to_matrix(v) -> np.ndarray:
    """(..., 4, 4) homogeneous matrices of versors."""
    a = to_affine(v)
    m = np.zeros(a.shape[:-2] + (4, 4))
    m[..., :3, :] = a
    m[..., 3, 3] = 1.0
    return m


def from_matrix(m, tolerance: float = 1e-6) -> np.ndarray:
    """Versor of (..., 4, 4) matrices that are rotation + translation + uniform scale.

    Raises InvalidInputError for shear, non-uniform scale, reflection or a bad last row: those are
    not similarities (keep them as matrices; see cgaskin.skin_affine)."""
    m = float_array(m, "matrix", 4)
    if m.shape[-2:] != (4, 4):
        raise InvalidInputError(f"matrix must have shape (..., 4, 4), got {m.shape}")
    if not np.allclose(m[..., 3, :], [0, 0, 0, 1], atol=tolerance):
        raise InvalidInputError("matrix last row must be (0, 0, 0, 1)")
    lin = m[..., :3, :3]
    det = np.linalg.det(lin)
    gram = np.swapaxes(lin, -1, -2) @ lin
    s2 = np.cbrt(det)[..., None, None] ** 2
    if np.any(det <= 0) or np.any(np.abs(gram - s2 * np.eye(3)) > tolerance * np.maximum(s2, 1e-300)):
        raise InvalidInputError("matrix is not a similarity (rotation, translation, positive uniform "
                                "scale): it has shear, non-uniform scale or a reflection")
    return _rows(K.versor_from_matrix_batch, VERSOR_SIZE, (m.reshape(m.shape[:-2] + (16,)), True))


def apply(v, points) -> np.ndarray:
    """Transform points (..., 3) by versors (..., 12) (broadcast): down(V up(x) Ṽ)."""
    affine = _rows(K.versor_to_affine_batch, 12, (_versor_arg(v), True))
    return _rows(K.affine_point_batch, 3, (affine, True), (float_array(points, "points", 3), True))


# ---- logarithm, exponential, blending -------------------------------------------------------------
def log(v) -> np.ndarray:
    """(..., 7) bivector coefficients on LOG_BLADES; exp(log(V)) == V (up to sign)."""
    return _rows(K.versor_log_batch, LOG_SIZE, (_versor_arg(v), True))


def exp(bivector) -> np.ndarray:
    """Versor exp(Λ_M) exp(λ e∞0) of (..., 7) coefficients on LOG_BLADES (inverse of ``log``)."""
    out = _rows(K.versor_exp_batch, VERSOR_SIZE, (float_array(bivector, "bivector", LOG_SIZE), True))
    if not np.isfinite(out).all():
        raise InvalidInputError("exp overflows float64: the bivector's scale coefficient (or its "
                                "translation) is too large for a finite versor")
    return out


def _blend_args(versors, weights):
    versors = _versor_arg(versors, "versors")
    weights = float_array(weights, "weights")
    if versors.ndim < 2 or weights.shape != versors.shape[:-1]:
        raise InvalidInputError(f"weights must have shape {versors.shape[:-1]} (one per versor), "
                                f"got {weights.shape}")
    # V and −V are the same transformation: align every versor with the first one (antipodality)
    sign = np.where(np.sum(versors[..., :1, :4] * versors[..., :4], axis=-1) < 0, -1.0, 1.0)
    return versors * sign[..., None], weights


def blend_linear(versors, weights) -> np.ndarray:
    """Normalised weighted sum of versors (..., k, 12) with weights (..., k)."""
    versors, weights = _blend_args(versors, weights)
    return normalise(np.einsum("...k,...kc->...c", weights, versors))


def blend_log(versors, weights) -> np.ndarray:
    """Logarithmic blend P exp(Σ_i w_i log(P⁻¹ V_i)) of versors (..., k, 12) with weights (..., k)
    summing to 1, where the pivot P is the versor of largest weight (so that a weight of 1 returns
    its versor to rounding): two versors interpolate along the shortest screw motion between them
    (ScLERP, the short arc for rotations) with the scale interpolated geometrically. For commuting
    versors (one rotation axis, pure translations, pure scales) it equals exp(Σ_i w_i log V_i)."""
    versors, weights = _blend_args(versors, weights)
    pivot = np.take_along_axis(versors, np.argmax(weights, axis=-1)[..., None, None], axis=-2)
    # the sign of each versor that puts its rotor within a quarter turn of the pivot's (short arc)
    sign = np.where(np.sum(pivot[..., :4] * versors[..., :4], axis=-1) < 0, -1.0, 1.0)
    relative = compose(inverse(pivot), versors * sign[..., None])
    return compose(pivot[..., 0, :], exp(np.einsum("...k,...kc->...c", weights, log(relative))))


# ---- interop with the clifford package (test/oracle dependency) -----------------------------------
def _clifford_basis():
    from clifford import g3c
    e1, e2, e3, einf, eo = g3c.e1, g3c.e2, g3c.e3, g3c.einf, g3c.eo
    vectors = {"1": e1, "2": e2, "3": e3, "∞": einf, "0": eo}
    blades = []
    for name in VERSOR_BLADES:
        blade = 1.0 + 0 * e1
        if name != "1":
            for ch in name[1:]:
                blade = blade ^ vectors[ch]
        blades.append(blade)
    return g3c, blades


def to_clifford(v):
    """A ``clifford.g3c`` multivector (or a list, for batches) equal to the versor."""
    _, blades = _clifford_basis()
    arr = float_array(v, "versor", VERSOR_SIZE)
    if arr.ndim == 1:
        return sum((c * b for c, b in zip(arr, blades)), 0 * blades[0])
    return [to_clifford(row) for row in arr.reshape(-1, VERSOR_SIZE)]


def from_clifford(mv, tolerance: float = 1e-9) -> np.ndarray:
    """The (12,) versor array of a ``clifford.g3c`` multivector; error if it has other blades."""
    _, blades = _clifford_basis()
    basis = np.stack([b.value for b in blades], axis=1)          # (32, 12)
    coeffs, *_ = np.linalg.lstsq(basis, mv.value, rcond=None)
    rest = mv.value - basis @ coeffs
    if np.max(np.abs(rest)) > tolerance * max(1.0, np.max(np.abs(mv.value))):
        raise InvalidInputError("the multivector has components outside the 12-blade versor type")
    return coeffs
