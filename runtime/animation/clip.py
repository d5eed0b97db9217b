"""Animation clips (``Channel``, ``Clip``) and their packed form for the compiled sampler.

A clip is sampled with glTF 2.0 semantics by ``sampling.py`` (one compiled call per frame, or per
batch of frames): translation and scale channels interpolate componentwise (STEP, LINEAR,
CUBICSPLINE), rotation channels by glTF's shortest-path slerp (or, with ``rotation_blend="linear"``,
the normalised linear blend); times before the first key clamp to the first value, after the last key
to the last value. ``Clip.packed`` lays every channel of a clip out once in flat arrays with integer
codes, which is what the sampler reads.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import NamedTuple

import numpy as np

from .._shared.frozen import frozen
from ..errors import InvalidInputError

INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")
CHANNEL_PATHS = {"translation": 3, "rotation": 4, "scale": 3}
ROTATION_BLENDS = ("slerp", "linear")

#: integer codes of the packed arrays: each is the name's index in the tuple above
STEP, LINEAR, CUBICSPLINE = 0, 1, 2
TRANSLATION, ROTATION, SCALE = 0, 1, 2
SLERP, NLERP = 0, 1

#: columns of ``ClipArrays.channels``
NODE, PATH, INTERPOLATION, FIRST_KEY, KEYS, FIRST_VALUE = range(6)
#: a STEP or LINEAR rotation key in ``ClipArrays.values``: the unit quaternion (x, y, z, w), then the
#: arc to the next key that slerp needs (the sign that puts the next key on the shorter arc, the angle
#: θ between them, 1 / sin θ and cos θ; zeros after the last key), so that a frame pays one sincos
ARC_SIGN, ARC_ANGLE, ARC_INV_SIN, ARC_COS, ROTATION_KEY = 4, 5, 6, 7, 8


@dataclass(frozen=True, eq=False)
class Channel:
    """One animated property of one node: its keys and how they interpolate (glTF's semantics).

    Parameters
    ----------
    node : int
        Index into ``Skeleton.names``.
    path : {"translation", "rotation", "scale"}
        The property animated.
    interpolation : {"STEP", "LINEAR", "CUBICSPLINE"}
        How values between keys are made.
    times : (k,) float64
        Key times in seconds, strictly increasing.
    values : (k, c) or (k, 3, c) float64
        Key values, c = 3 for translation and scale, 4 (x, y, z, w) for rotation; CUBICSPLINE keys
        are (in-tangent, value, out-tangent). ``times`` and ``values`` are kept as read-only copies.

    Examples
    --------
    >>> channel = cgaskin.capsule_arm().clips[0].channels[1]            # the elbow of "wave"
    >>> channel.node, channel.path, channel.interpolation, channel.values.shape
    (1, 'rotation', 'LINEAR', (5, 4))
    >>> step = cgaskin.Channel(0, "translation", "STEP", [0.0, 1.0], [[0, 0, 0], [0, 1, 0]])
    """

    node: int
    path: str
    interpolation: str
    times: np.ndarray
    values: np.ndarray

    def __post_init__(self):
        # read-only copies, as a rig's arrays: a clip's packed arrays are kept (``Clip.packed``), so
        # an edit in place would be silently ignored
        for name in ("times", "values"):
            object.__setattr__(self, name, frozen(np.array(getattr(self, name))))

    def __reduce__(self):                    # (unpickled: read-only again)
        return Channel, (self.node, self.path, self.interpolation, self.times, self.values)


class ClipArrays(NamedTuple):
    """Every channel of a clip in flat arrays (what the compiled sampler reads).

    channels : (c, 6) int64 rows (node, path code, interpolation code, first key, key count,
        first value), columns named by ``NODE``, ``PATH``, ... ; codes as ``TRANSLATION``, ``STEP``, ...
    times : (K,) float64, the key times of every channel one after the other
    values : (V,) float64, the values of every channel flattened in their (k, c) or (k, 3, c) order;
        STEP and LINEAR rotation keys as (k, ``ROTATION_KEY``) rows: a unit quaternion and its arc
    nodes : (a,) int64, the animated nodes, ascending
    last_node : int, the largest animated node (-1: none)
    """

    channels: np.ndarray
    times: np.ndarray
    values: np.ndarray
    nodes: np.ndarray
    last_node: int


@dataclass(frozen=True, eq=False)
class Clip:
    """A named animation: a set of channels. ``duration`` is the last key time.

    Channels are values: their arrays are read-only copies (``packed`` flattens them once and keeps
    the result for the clip's lifetime).

    Parameters
    ----------
    name : str
        The clip's name (what ``Rig.pose`` and ``cgaskin view`` select it by).
    channels : sequence of Channel
        Its animated properties; kept as a tuple.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> lift = cgaskin.Clip("lift", [cgaskin.Channel(0, "translation", "LINEAR", [0.0, 2.0],
    ...                                              [[0, 0, 0], [0, 1, 0]])])
    >>> lift.duration, arm.with_clips(lift).clip_index("lift")
    (2.0, 1)
    """

    name: str
    channels: tuple[Channel, ...]

    def __post_init__(self):
        object.__setattr__(self, "channels", tuple(self.channels))

    def __reduce__(self):                    # (its packed arrays are made again when sampled)
        return Clip, (self.name, self.channels)

    @property
    def duration(self) -> float:
        return max((float(c.times[-1]) for c in self.channels), default=0.0)

    @cached_property
    def packed(self) -> ClipArrays:
        """The channels in flat arrays, checked and built on first use (then cached with the clip)."""
        return pack_channels(self.name, self.channels)


def _with_arcs(keys):
    """(k, ``ROTATION_KEY``) of unit quaternion keys (k, 4): each with the arc to the next key. The
    angle comes from the chords |qa - qb| = 2 sin(θ/2) and |qa + qb| = 2 cos(θ/2) (accurate at small
    angles, where acos of the dot product loses half the digits); sin θ = 2 sin(θ/2) cos(θ/2) and
    cos θ = cos²(θ/2) - sin²(θ/2) from the same chords."""
    rows = np.zeros((len(keys), ROTATION_KEY))
    rows[:, :4] = keys
    a, b = keys[:-1], keys[1:]
    sign = np.where(np.einsum("ij,ij->i", a, b) < 0.0, -1.0, 1.0)   # q and -q are one rotation
    d2 = ((a - sign[:, None] * b) ** 2).sum(axis=1)
    s2 = ((a + sign[:, None] * b) ** 2).sum(axis=1)
    chord_d, chord_s = np.sqrt(d2), np.sqrt(s2)
    rows[:-1, ARC_SIGN] = sign
    rows[:-1, ARC_ANGLE] = 2.0 * np.arctan2(chord_d, chord_s)
    with np.errstate(divide="ignore"):        # θ = 0: slerp is the linear blend, 1 / sin θ unused
        rows[:-1, ARC_INV_SIN] = 2.0 / (chord_d * chord_s)
    rows[:-1, ARC_COS] = 0.25 * (s2 - d2)
    return rows


def pack_channels(name: str, channels) -> ClipArrays:
    """``ClipArrays`` of ``channels``; InvalidInputError names the clip and channel that is malformed
    (unknown path or interpolation, times not finite and strictly increasing, values of the wrong
    shape or not finite)."""
    rows, times, values = [], [], []
    n_keys = n_values = 0
    for c, channel in enumerate(channels):
        where = f"clip {name!r} channel {c}"
        if channel.path not in CHANNEL_PATHS:
            raise InvalidInputError(f"{where}: path must be one of {tuple(CHANNEL_PATHS)}, got {channel.path!r}")
        if channel.interpolation not in INTERPOLATIONS:
            raise InvalidInputError(f"{where}: interpolation must be one of {INTERPOLATIONS}, "
                                    f"got {channel.interpolation!r}")
        if isinstance(channel.node, bool) or not isinstance(channel.node, (int, np.integer)) or channel.node < 0:
            raise InvalidInputError(f"{where}: node must be a node index >= 0, got {channel.node!r}")
        t = np.asarray(channel.times, dtype=np.float64)
        v = np.asarray(channel.values, dtype=np.float64)
        width = CHANNEL_PATHS[channel.path]
        cubic = channel.interpolation == "CUBICSPLINE"
        shape = (len(t), 3, width) if cubic else (len(t), width)
        if t.ndim != 1 or len(t) == 0 or not np.isfinite(t).all() or (np.diff(t) <= 0).any():
            raise InvalidInputError(f"{where}: times must be a non-empty 1-D array of finite, strictly "
                                    f"increasing seconds")
        if v.shape != shape or not np.isfinite(v).all():
            raise InvalidInputError(f"{where}: {channel.interpolation} {channel.path} values must be finite "
                                    f"with shape {shape}, got {v.shape}")
        if channel.path == "rotation" and not cubic:
            # unit keys once here, so that the sampler blends them as they are (a cubic spline's
            # tangents are not rotations: its keys stay as given, its result is normalised)
            norm = np.linalg.norm(v, axis=1, keepdims=True)
            if not (norm > 0).all():
                raise InvalidInputError(f"{where}: rotation key {int(np.argmin(norm))} has zero length")
            v = _with_arcs(v / norm)
        rows.append((channel.node, list(CHANNEL_PATHS).index(channel.path),
                     INTERPOLATIONS.index(channel.interpolation), n_keys, len(t), n_values))
        times.append(t)
        values.append(v.reshape(-1))
        n_keys += len(t)
        n_values += v.size
    table = np.array(rows, dtype=np.int64).reshape(-1, 6)
    nodes = np.unique(table[:, NODE])
    return ClipArrays(channels=table, times=np.concatenate(times) if times else np.empty(0),
                      values=np.concatenate(values) if values else np.empty(0), nodes=nodes,
                      last_node=int(nodes[-1]) if len(nodes) else -1)
