"""Clip sampling in compiled code: a clip at a time (or at many times) straight into a pose's fields.

One kernel call does a whole frame: for every channel of the clip (``Clip.packed``: flat arrays and
integer codes, built once per clip) it finds the key interval (the clip's cursor first: the interval
of the channel's last frame, then the next one, as a playback rarely leaves them; else a binary
search), interpolates with glTF 2.0 semantics into the node's TRS, and then composes each animated
node's TRS into the pose's fields:

* STEP holds the key's value; LINEAR blends translation and scale componentwise and rotations by
  glTF's slerp along the shorter arc (``rotation_blend="linear"``: the normalised linear blend);
  CUBICSPLINE is the Hermite spline with tangents scaled by the key interval, rotations normalised;
* a time before the first key clamps to the first value, after the last key to the last value;
* a node no channel animates keeps its rest transform (its exact matrix where the rest TRS is only an
  approximation, a shear); an animated node is TRS, as glTF defines it;
* a node whose scale is uniform and positive is a similarity: its versor is T R D through the
  generated kernels (``versor_translator``, ``versor_rotor_quaternion``, ``versor_dilator``, the
  motor product T R by ``gp_motor_motor``, then ``gp_versor_versor`` with D unless the scale is 1);
  every node also gets its exact matrix T @ R @ S — the fields that ``Pose.from_trs`` makes of the
  same TRS (equal to rounding; tests/animation/test_sampling.py checks 1e-12).

A frame starts as copies of the rest pose's fields (the nodes no channel animates keep them), and the
kernel writes the animated nodes. Slerp reads the angle between two keys, kept beside the first of them
(``clip.ROTATION_KEY`` rows), so a frame pays one sincos per rotation channel.

A frame costs microseconds, so what surrounds the kernel counts as much as the kernel (numba's
dispatch of its arguments, the fields copied from the rest, the Pose; ``benchmarks/bench_animation.py``
measures each). The frame, its channels and its nodes are each typed into the kernels (``inlined``),
not called: a compiled call that takes arrays pays their reference counts (atomic operations), a
large share of a frame as a call per channel and per node.

The rest of the skeleton (TRS rows, and the rest pose's fields that unanimated nodes keep) is
prepared once per skeleton, by the same kernel with no channels.
"""
from __future__ import annotations

import math
import weakref
from typing import NamedTuple

import numpy as np

from .._shared.checks import float_array, real_number
from .._shared.jit import B1, B2, F1, F2, F3, F4, I1, I2, f8, helper, i8, inlined, kernel
from .._shared.memory_budget import require_memory
from ..algebra.transforms import trs_matrix
from ..algebra.versor import SCALE_RANGE
from ..errors import InvalidInputError
from ..generated.kernels import (gp_motor_motor, gp_versor_versor, versor_dilator, versor_rotor_quaternion,
                                 versor_translator)
from ..tolerances import tol
from .clip import (ARC_ANGLE, ARC_COS, ARC_INV_SIN, ARC_SIGN, CUBICSPLINE, FIRST_KEY, FIRST_VALUE, INTERPOLATION,
                   KEYS, NLERP, NODE, PATH, ROTATION, ROTATION_BLENDS, ROTATION_KEY, SCALE, SLERP, STEP,
                   pack_channels)

#: a node's TRS row in the kernels' scratch: translation, rotation (x, y, z, w), scale
TRS_T, TRS_Q, TRS_S, TRS_SIZE = 0, 3, 7, 10
#: what a sampling kernel reports: every node composed, or the first node that could not be
OK, SCALE_OUT_OF_RANGE, NOT_FINITE = 0, 1, 2
_SCALE_LOW, _SCALE_HIGH = SCALE_RANGE
_EMPTY = pack_channels("rest", ())
_BLEND_CODES = {"slerp": SLERP, "linear": NLERP}


# ---- the kernels -----------------------------------------------------------------------------------
@helper
def _key(times, first, count, t, hint):
    """(k, u, dt): the interval [k, k+1] of the channel's keys times[first:first+count] that holds t,
    u in [0, 1) the fraction of it, dt its length; k = 0 or count - 1 with u = 0 when t clamps.
    ``hint``: the interval of the previous frame, tried (and the next one) before a binary search."""
    last = first + count - 1
    if t <= times[first]:
        return 0, 0.0, 0.0
    if t >= times[last]:
        return count - 1, 0.0, 0.0
    k = hint
    if not (k < count - 1 and times[first + k] <= t < times[first + k + 1]):
        k = hint + 1
        if not (k < count - 1 and times[first + k] <= t < times[first + k + 1]):
            lo, hi = 0, count - 1               # times[first + lo] <= t < times[first + hi]
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if times[first + mid] <= t:
                    lo = mid
                else:
                    hi = mid
            k = lo
    dt = times[first + k + 1] - times[first + k]
    return k, (t - times[first + k]) / dt, dt


@helper
def _blend_rotation(values, a, u, blend, out, node, at):
    """out[node, at:at+4] = the unit quaternion between the rotation key at values[a] and the next
    one (each a ``ROTATION_KEY`` row: the key, then its arc to the next) at u, on the shorter arc:
    slerp (glTF), or with blend NLERP the normalised linear blend."""
    b = a + ROTATION_KEY
    wa, wb = 1.0 - u, u
    theta = values[a + ARC_ANGLE]
    if blend != NLERP and theta > 0.0:
        # wb = sin uθ / sin θ, wa = sin (1-u)θ / sin θ = cos uθ - cos θ wb: one angle's sine and cosine
        # (one sincos call; θ <= π/2 on the shorter arc, so sin θ is not small unless θ is, and then
        # wb -> u, wa -> 1 - u with absolute errors of a few ulps)
        wb = math.sin(u * theta) * values[a + ARC_INV_SIN]
        wa = math.cos(u * theta) - values[a + ARC_COS] * wb
    wb *= values[a + ARC_SIGN]
    q0 = wa * values[a] + wb * values[b]
    q1 = wa * values[a + 1] + wb * values[b + 1]
    q2 = wa * values[a + 2] + wb * values[b + 2]
    q3 = wa * values[a + 3] + wb * values[b + 3]
    inv_norm = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    out[node, at] = q0 * inv_norm
    out[node, at + 1] = q1 * inv_norm
    out[node, at + 2] = q2 * inv_norm
    out[node, at + 3] = q3 * inv_norm


@inlined
def _sample_channels(channels, times, values, t, blend, hints, trs):
    """Write every channel (the rows of ``ClipArrays.channels``) at time t into its node's TRS row.
    (Rows are indexed, never taken as views: a view is an array whose reference count costs.)"""
    for c in range(channels.shape[0]):
        node, path, interpolation = channels[c, NODE], channels[c, PATH], channels[c, INTERPOLATION]
        width = 4 if path == ROTATION else 3
        at = TRS_Q if path == ROTATION else (TRS_S if path == SCALE else TRS_T)
        k, u, dt = _key(times, channels[c, FIRST_KEY], channels[c, KEYS], t, hints[c])
        hints[c] = k
        if interpolation == CUBICSPLINE:
            stride, middle = 3 * width, width   # a cubic key is (in-tangent, value, out-tangent)
        else:
            stride, middle = (ROTATION_KEY if path == ROTATION else width), 0
        here = channels[c, FIRST_VALUE] + k * stride + middle
        if u == 0.0 or interpolation == STEP:
            for i in range(width):
                trs[node, at + i] = values[here + i]
        elif interpolation == CUBICSPLINE:
            # Hermite basis; the out-tangent of key k follows its value, the in-tangent of k+1 precedes it
            u2, u3 = u * u, u * u * u
            there = here + stride
            for i in range(width):
                trs[node, at + i] = ((2 * u3 - 3 * u2 + 1) * values[here + i]
                                     + (u3 - 2 * u2 + u) * dt * values[here + width + i]
                                     + (-2 * u3 + 3 * u2) * values[there + i]
                                     + (u3 - u2) * dt * values[there - width + i])
        elif path == ROTATION:
            _blend_rotation(values, here, u, blend, trs, node, at)
            continue
        else:
            for i in range(width):
                trs[node, at + i] = (1 - u) * values[here + i] + u * values[here + stride + i]
        if path == ROTATION:
            norm = 0.0
            for i in range(4):
                norm += trs[node, at + i] * trs[node, at + i]
            inv_norm = 1.0 / math.sqrt(norm)
            for i in range(4):
                trs[node, at + i] *= inv_norm


@inlined
def _compose_nodes(trs, nodes, versors, matrices, similar):
    """The fields of each node of ``nodes`` from its TRS row: versor T R D (identity unless the scale is
    uniform and positive), matrix T @ R @ S (as ``trs_matrix``) and whether it is a similarity. Returns
    (status, the first node that failed)."""
    for a in range(nodes.shape[0]):
        node = nodes[a]
        x, y, z, w = trs[node, TRS_Q], trs[node, TRS_Q + 1], trs[node, TRS_Q + 2], trs[node, TRS_Q + 3]
        sx, sy, sz = trs[node, TRS_S], trs[node, TRS_S + 1], trs[node, TRS_S + 2]
        tx, ty, tz = trs[node, TRS_T], trs[node, TRS_T + 1], trs[node, TRS_T + 2]
        is_similar = sx == sy and sx == sz and sx > 0.0
        if is_similar and not _SCALE_LOW <= sx <= _SCALE_HIGH:
            similar[node] = is_similar
            return SCALE_OUT_OF_RANGE, node     # a dilation float64 cannot hold (versor.dilator refuses it)
        finite = 0.0
        if is_similar:
            # T R as motors (the product of 8 blades; T and R have no e∞0 part), then the dilator
            m = gp_motor_motor(versor_translator((tx, ty, tz)), versor_rotor_quaternion((x, y, z, w)))
            v = (m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], 0.0, 0.0, 0.0, 0.0)
            if sx != 1.0:       # the dilator of 1 is the identity (the product would only add zeros)
                v = gp_versor_versor(v, versor_dilator(sx))
            for c in range(12):
                versors[node, c] = v[c]
                finite += v[c] * 0.0
        else:
            for c in range(12):
                versors[node, c] = 0.0
            versors[node, 0] = 1.0
        inv_n = 1.0 / math.sqrt(x * x + y * y + z * z + w * w)
        x, y, z, w = x * inv_n, y * inv_n, z * inv_n, w * inv_n
        # the rotation matrix of the unit quaternion (as quat_to_matrix), its columns scaled (R @ S)
        m00, m01, m02 = (1 - 2 * (y * y + z * z)) * sx, 2 * (x * y - z * w) * sy, 2 * (x * z + y * w) * sz
        m10, m11, m12 = 2 * (x * y + z * w) * sx, (1 - 2 * (x * x + z * z)) * sy, 2 * (y * z - x * w) * sz
        m20, m21, m22 = 2 * (x * z - y * w) * sx, 2 * (y * z + x * w) * sy, (1 - 2 * (x * x + y * y)) * sz
        matrices[node, 0, 0], matrices[node, 0, 1], matrices[node, 0, 2], matrices[node, 0, 3] = m00, m01, m02, tx
        matrices[node, 1, 0], matrices[node, 1, 1], matrices[node, 1, 2], matrices[node, 1, 3] = m10, m11, m12, ty
        matrices[node, 2, 0], matrices[node, 2, 1], matrices[node, 2, 2], matrices[node, 2, 3] = m20, m21, m22, tz
        matrices[node, 3, 0], matrices[node, 3, 1], matrices[node, 3, 2], matrices[node, 3, 3] = 0.0, 0.0, 0.0, 1.0
        finite += (m00 * 0.0 + m01 * 0.0 + m02 * 0.0 + tx * 0.0 + m10 * 0.0 + m11 * 0.0 + m12 * 0.0 + ty * 0.0
                   + m20 * 0.0 + m21 * 0.0 + m22 * 0.0 + tz * 0.0)
        similar[node] = is_similar
        if finite != 0.0:                   # NaN * 0 and inf * 0 are NaN
            return NOT_FINITE, node
    return OK, -1


@inlined
def _sample_into(channels, times, values, nodes, rest_trs, t, blend, hints, trs, versors, matrices, similar):
    """One frame: the clip's channels at t into the animated nodes' TRS rows (from their rest TRS),
    composed into their fields (the other nodes' fields hold the rest's already). Returns (status,
    the first node that failed)."""
    for a in range(nodes.shape[0]):
        for c in range(TRS_SIZE):
            trs[nodes[a], c] = rest_trs[nodes[a], c]
    _sample_channels(channels, times, values, t, blend, hints, trs)
    return _compose_nodes(trs, nodes, versors, matrices, similar)


@kernel((I2, F1, F1, I1, F2, I1, f8, i8, F2, F3, B1), cost=2.0)
def _sample_pose(channels, times, values, nodes, rest_trs, hints, t, blend, versors, matrices, similar):
    """One frame of a clip into versors (j, 12), matrices (j, 4, 4), similar (j,), which hold the rest
    pose's fields (the nodes no channel animates keep them); returns (status, node). ``hints`` (c,):
    each channel's key interval of the clip's last frame, updated (a cursor: the next frame of a
    playback rarely leaves it)."""
    trs = np.empty((rest_trs.shape[0], TRS_SIZE))
    return _sample_into(channels, times, values, nodes, rest_trs, t, blend, hints, trs, versors, matrices,
                        similar)


@kernel((I2, F1, F1, I1, F2, I1, F1, i8, F3, F4, B2), cost=1.6)
def _sample_poses(channels, times, values, nodes, rest_trs, hints, frame_times, blend, versors, matrices,
                  similar):
    """Frames at frame_times (T,) into versors (T, j, 12), matrices (T, j, 4, 4), similar (T, j), each
    frame holding the rest pose's fields; returns (status, node, frame) of the first failure (status
    OK: none). Each channel's key interval of the previous frame is tried first: increasing times
    search only when they cross a key."""
    trs = np.empty((rest_trs.shape[0], TRS_SIZE))
    for f in range(frame_times.shape[0]):
        status, node = _sample_into(channels, times, values, nodes, rest_trs, frame_times[f], blend, hints,
                                    trs, versors[f], matrices[f], similar[f])
        if status != OK:
            return status, node, f
    return OK, -1, -1


# ---- the Python side ----------------------------------------------------------------------------------
_REST = weakref.WeakKeyDictionary()            # skeleton -> its rest arrays, while it lives
_ARGUMENTS = weakref.WeakKeyDictionary()       # clip -> (skeleton, kernel arguments), while the clip lives


def shear_nodes(skeleton) -> list:
    """Per node: its exact rest matrix when the stored TRS does not reproduce it, else None."""
    trs = trs_matrix(skeleton.rest_translations, skeleton.rest_rotations, skeleton.rest_scales)
    out = []
    for m, exact in zip(trs, skeleton.rest_matrices):
        out.append(None if np.allclose(m, exact, rtol=0, atol=tol.trs_exact * max(1.0, np.abs(exact).max())) else exact)
    return out


class RestFields(NamedTuple):
    """A skeleton's rest made ready for sampling: the TRS rows (j, 10) every animated node starts
    from, and the fields of ``Pose.rest`` (versors (j, 12), matrices (j, 4, 4), similar (j,)), which
    every frame starts as (the nodes no channel animates keep them)."""

    trs: np.ndarray
    versors: np.ndarray
    matrices: np.ndarray
    similar: np.ndarray


def _rest(skeleton) -> RestFields:
    """The skeleton's ``RestFields``, made by the sampling kernel itself with no channels: every node
    whose TRS reproduces its rest matrix composed from it, the others (shear) kept as their matrix."""
    rest = _REST.get(skeleton)
    if rest is None:
        j = skeleton.n_nodes
        trs = np.ascontiguousarray(np.concatenate([skeleton.rest_translations, skeleton.rest_rotations,
                                                   skeleton.rest_scales], axis=1), dtype=np.float64)
        exact = shear_nodes(skeleton)
        versors = np.zeros((j, 12))
        versors[:, 0] = 1.0
        matrices = np.array(skeleton.rest_matrices, dtype=np.float64, order="C")   # writable C: one kernel type
        similar = np.zeros(j, dtype=bool)
        computed = np.array([i for i in range(j) if exact[i] is None], dtype=np.int64)
        status, node = _sample_pose(_EMPTY.channels, _EMPTY.times, _EMPTY.values, computed, trs,
                                    np.zeros(0, dtype=np.int64), 0.0, 0, versors, matrices, similar)
        _check(status, node, "the rest pose", skeleton)
        rest = _REST[skeleton] = RestFields(trs, versors, matrices, similar)
    return rest


def _check(status, node, what: str, skeleton) -> None:
    if status == SCALE_OUT_OF_RANGE:
        low, high = SCALE_RANGE
        raise InvalidInputError(f"{what}: node {skeleton.names[node]!r} has a uniform scale outside "
                                f"[{low:g}, {high:g}], which a dilation in float64 cannot hold")
    if status == NOT_FINITE:
        raise InvalidInputError(f"{what}: node {skeleton.names[node]!r} has a transform that is not finite "
                                f"(a zero-length rotation, or values that overflow float64)")


class FrameSampler(NamedTuple):
    """A clip made ready to sample on a skeleton, after every check that does not depend on the time:
    the kernels' arguments before the time (the packed clip's arrays, the rest TRS rows, the
    channels' cursor), the rotation blend's code, and the rest fields a frame starts as."""

    skeleton: object
    clip: object
    arguments: tuple
    blend: int
    rest: RestFields


def frame_sampler(skeleton, clip, rotation_blend: str = "slerp") -> FrameSampler:
    """``clip`` made ready to sample on ``skeleton``; InvalidInputError for an unknown
    ``rotation_blend`` or a clip that animates nodes the skeleton lacks. The arguments are kept with
    the clip for the last skeleton it was sampled on. The cursor (each channel's last key interval)
    is shared by the clip's calls: the kernel only tries it before searching, so calls in other
    threads or out of order stay exact."""
    blend = _BLEND_CODES.get(rotation_blend) if isinstance(rotation_blend, str) else None
    if blend is None:
        raise InvalidInputError(f"rotation_blend must be one of {ROTATION_BLENDS}, got {rotation_blend!r}")
    kept = _ARGUMENTS.get(clip)
    if kept is None or kept[0] is not skeleton:
        packed = clip.packed
        if packed.last_node >= skeleton.n_nodes:
            raise InvalidInputError(f"clip {clip.name!r} animates node {packed.last_node}, but the skeleton "
                                    f"has {skeleton.n_nodes} nodes")
        rest = _rest(skeleton)
        cursor = np.zeros(len(packed.channels), dtype=np.int64)
        kept = _ARGUMENTS[clip] = (skeleton, (packed.channels, packed.times, packed.values, packed.nodes,
                                              rest.trs, cursor), rest)
    return FrameSampler(skeleton, clip, kept[1], blend, kept[2])


def sample_frame(sampler: FrameSampler, t: float) -> tuple:
    """The fields of the sampler's clip at ``t`` (a finite float, seconds; times outside the keys clamp,
    as glTF says): versors (j, 12) float64, matrices (j, 4, 4) float64, similar (j,) bool, as ``Pose``
    holds them, in one compiled call."""
    rest = sampler.rest
    versors, matrices, similar = rest.versors.copy(), rest.matrices.copy(), rest.similar.copy()
    status, node = _sample_pose(*sampler.arguments, t, sampler.blend, versors, matrices, similar)
    if status != OK:
        _check(status, node, f"clip {sampler.clip.name!r} at t={t}", sampler.skeleton)
    return versors, matrices, similar


def sample_pose(skeleton, clip, time, rotation_blend: str = "slerp") -> tuple:
    """``sample_frame`` of ``clip`` on ``skeleton`` at ``time``; InvalidInputError for a time that is
    not a finite real number, an unknown ``rotation_blend``, or a clip that does not fit the skeleton."""
    return sample_frame(frame_sampler(skeleton, clip, rotation_blend), real_number(time, "time"))


#: a pose's bytes per joint: its versor (12 float64), matrix (16) and similarity flag
POSE_BYTES = 8 * (12 + 16) + 1


def sample_poses(skeleton, clip, times, rotation_blend: str = "slerp") -> tuple:
    """``sample_pose`` at each of ``times`` ((T,) finite seconds, any order): versors (T, j, 12),
    matrices (T, j, 4, 4), similar (T, j), in one compiled call."""
    shape = np.shape(times)
    if len(shape) == 1:                       # (checked below; first the size: a copy of it is made)
        require_memory(shape[0] * (8 + POSE_BYTES * skeleton.n_nodes), f"times ({shape[0]} poses of "
                       f"{skeleton.n_nodes} joints)", "sample fewer times at once")
    times = np.array(float_array(times, "times", ndim=1), order="C")      # the caller's array stays theirs
    _, _, arguments, blend, rest = frame_sampler(skeleton, clip, rotation_blend)
    versors, matrices, similar = (np.repeat(field[None], len(times), axis=0)
                                  for field in (rest.versors, rest.matrices, rest.similar))
    status, node, frame = _sample_poses(*arguments, times, blend, versors, matrices, similar)
    if status != OK:
        _check(status, node, f"clip {clip.name!r} at t={times[frame]} (times[{frame}])", skeleton)
    return times, versors, matrices, similar
