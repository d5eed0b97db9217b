"""Animation clips (``Channel``, ``Clip``) and their sampling with glTF 2.0 semantics, rotations
through versors.

Translation and scale channels interpolate componentwise (STEP, LINEAR, CUBICSPLINE). Rotation
channels interpolate as rotors: LINEAR is the geodesic (slerp) R0 exp(u log(R̃0 R1)) through the
generated log/exp/product kernels — exactly glTF's slerp — or, with ``rotation_blend="linear"``, the
normalised linear blend of the two rotors. Times before the first key clamp to the first value, after
the last key to the last value.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared.checks import real_number
from ..algebra import versor
from ..errors import InvalidInputError

INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")


CHANNEL_PATHS = {"translation": 3, "rotation": 4, "scale": 3}


@dataclass(frozen=True, eq=False)
class Channel:
    """One animated property of one node.

    node : int, index into ``Skeleton.names``
    path : "translation" | "rotation" | "scale"
    interpolation : "STEP" | "LINEAR" | "CUBICSPLINE"
    times : (k,) float64, strictly increasing seconds
    values : (k, c) float64 for STEP/LINEAR, (k, 3, c) for CUBICSPLINE (in-tangent, value,
        out-tangent), with c = 3 for translation/scale and 4 (x, y, z, w) for rotation
    """

    node: int
    path: str
    interpolation: str
    times: np.ndarray
    values: np.ndarray


@dataclass(frozen=True, eq=False)
class Clip:
    """A named animation: a set of channels. ``duration`` is the last key time."""

    name: str
    channels: tuple[Channel, ...]

    @property
    def duration(self) -> float:
        return max((float(c.times[-1]) for c in self.channels), default=0.0)


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
    """(..., 4) quaternions (x, y, z, w) of (..., 12) rotors R = w − x e23 + y e13 − z e12."""
    return np.stack([-r[..., 3], r[..., 2], -r[..., 1], r[..., 0]], axis=-1)


def blend_rotations(q0, q1, u, rotation_blend: str = "slerp") -> np.ndarray:
    """Interpolate quaternions (k, 4) -> (k, 4) at fractions u (k,) as rotors.

    "slerp": R0 exp(u log(R̃0 R1)), the geodesic along the shorter arc (log takes the angle in
    [0, π]) — glTF's LINEAR rotation; "linear": the normalised blend (1−u) R0 + u R1."""
    r0, r1 = versor.rotor_from_quaternion(q0), versor.rotor_from_quaternion(q1)
    u = np.asarray(u, dtype=np.float64)
    if rotation_blend == "linear":
        blended = versor.blend_linear(np.stack([r0, r1], axis=-2), np.stack([1 - u, u], axis=-1))
    else:
        step = versor.compose(versor.reverse(r0), r1)
        blended = versor.compose(r0, versor.exp(u[:, None] * versor.log(step)))
    q = _quat_from_rotor(blended)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def sample_clip(clip: Clip, t: float, rotation_blend: str = "slerp") -> dict:
    """{(node, path): value} for every channel of ``clip`` at time ``t`` (seconds): (3,) for
    translation/scale, unit (4,) (x, y, z, w) for rotation. Rotations between keys are blended as
    rotors in one batch of kernel calls for the whole clip."""
    if rotation_blend not in ROTATION_BLENDS:
        raise InvalidInputError(f"rotation_blend must be one of {ROTATION_BLENDS}, got {rotation_blend!r}")
    t = real_number(t, "time")
    values = {}
    pending = []                                    # LINEAR rotations: (key, q0, q1, u)
    for channel in clip.channels:
        key = (channel.node, channel.path)
        data = channel.values
        k, u, dt = _segment(channel.times, t)
        cubic = channel.interpolation == "CUBICSPLINE"
        if u == 0.0 or channel.interpolation == "STEP":
            value = np.array(data[k, 1] if cubic else data[k], dtype=np.float64)
        elif cubic:
            u2, u3 = u * u, u * u * u
            value = ((2 * u3 - 3 * u2 + 1) * data[k, 1] + (u3 - 2 * u2 + u) * dt * data[k, 2]
                     + (-2 * u3 + 3 * u2) * data[k + 1, 1] + (u3 - u2) * dt * data[k + 1, 0])
        elif channel.path == "rotation":
            pending.append((key, data[k], data[k + 1], u))
            continue
        else:
            value = (1 - u) * data[k] + u * data[k + 1]
        if channel.path == "rotation":
            value = value / np.linalg.norm(value)
        values[key] = value
    if pending:
        keys, q0, q1, u = zip(*pending)
        for key, q in zip(keys, blend_rotations(np.array(q0), np.array(q1), np.array(u), rotation_blend)):
            values[key] = q
    return values
