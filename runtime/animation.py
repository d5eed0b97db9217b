"""Sampling animation clips with glTF 2.0 semantics, rotations through versors.

Translation and scale channels interpolate componentwise (STEP, LINEAR, CUBICSPLINE). Rotation
channels interpolate as rotors: LINEAR is the geodesic (slerp) R0 exp(u log(R̃0 R1)) through the
generated log/exp/product kernels — exactly glTF's slerp — or, with ``rotation_blend="linear"``, the
normalised linear blend of the two rotors. Times before the first key clamp to the first value, after
the last key to the last value.
"""
from __future__ import annotations

import numpy as np

from . import versor
from .errors import InvalidInputError
from .rig import Channel, Clip

ROTATION_BLENDS = ("slerp", "linear")


def _segment(times: np.ndarray, t: float):
    """(k, u, dt): key interval [k, k+1] holding t and the fraction u in [0, 1]; k = -1 / len-1 clamp."""
    if t <= times[0]:
        return 0, 0.0, 0.0
    if t >= times[-1]:
        return len(times) - 1, 0.0, 0.0
    k = int(np.searchsorted(times, t, side="right")) - 1
    dt = float(times[k + 1] - times[k])
    return k, (t - times[k]) / dt, dt


def _quat_from_rotor(r):
    return np.array([-r[3], r[2], -r[1], r[0]])


def _rotor(q):
    return versor.rotor_from_quaternion(q)


def sample_channel(channel: Channel, t: float, rotation_blend: str = "slerp") -> np.ndarray:
    """Value of one channel at time t: (3,) for translation/scale, (4,) unit (x, y, z, w) for rotation."""
    times, values = channel.times, channel.values
    k, u, dt = _segment(times, t)
    cubic = channel.interpolation == "CUBICSPLINE"
    key = (lambda i: values[i, 1]) if cubic else (lambda i: values[i])
    if u == 0.0 or channel.interpolation == "STEP":
        value = np.array(key(k), dtype=np.float64)
    elif cubic:
        u2, u3 = u * u, u * u * u
        value = ((2 * u3 - 3 * u2 + 1) * values[k, 1] + (u3 - 2 * u2 + u) * dt * values[k, 2]
                 + (-2 * u3 + 3 * u2) * values[k + 1, 1] + (u3 - u2) * dt * values[k + 1, 0])
    elif channel.path != "rotation":
        value = (1 - u) * values[k] + u * values[k + 1]
    else:
        r0, r1 = _rotor(values[k]), _rotor(values[k + 1])
        if rotation_blend == "linear":
            value = _quat_from_rotor(versor.blend_linear(np.stack([r0, r1]), [1 - u, u]))
        else:
            # slerp along the shorter arc: R0 exp(u log(R̃0 R1)); log takes the angle in [0, π]
            step = versor.compose(versor.reverse(r0), r1)
            value = _quat_from_rotor(versor.compose(r0, versor.exp(u * versor.log(step))))
    if channel.path == "rotation":
        value = value / np.linalg.norm(value)
    return value


def sample_clip(clip: Clip, t: float, rotation_blend: str = "slerp") -> dict:
    """{(node, path): value} for every channel of ``clip`` at time ``t`` (seconds)."""
    if rotation_blend not in ROTATION_BLENDS:
        raise InvalidInputError(f"rotation_blend must be one of {ROTATION_BLENDS}, got {rotation_blend!r}")
    t = float(t)
    if not np.isfinite(t):
        raise InvalidInputError(f"time must be finite, got {t}")
    return {(c.node, c.path): sample_channel(c, t, rotation_blend) for c in clip.channels}
