"""The JSON messages of ``cgaskin serve``, checked into typed values before anything acts on them.

Every message from a page (or anything else that reaches the port) is untrusted: ``parse`` turns its
text into one of the request types below or raises ``ProtocolError`` naming what is wrong, so that
the session only ever sees finite float64 arrays of the right shapes, known operations, bounded
strings and numbers. Nothing a message holds is used as a path (``save`` replies with the bytes).

Requests (client -> server), each a JSON object with ``"op"`` and an optional ``"id"`` (an integer
or a string of at most 64 characters, echoed in the reply):

* ``{"op": "hello"}``: the model's name, counts, clips and joints, and the size of the whole mesh
* ``{"op": "tear", "from": [[x, y, z], [x, y, z]], "to": [[...], [...]], "opening": 0.0, POSE}``:
  one scalpel stroke (handle, tip at the previous and at this step)
* ``{"op": "cut", "normal": [x, y, z], "point": [x, y, z], "cap": false, POSE}``
* ``{"op": "drill", "start": [x, y, z], "end": [x, y, z], "radius": r, "wall": true, POSE}``
* ``{"op": "undo"}``, ``{"op": "save"}``

POSE: ``"clip": NAME`` (or null: the stored mesh), ``"time": seconds`` and ``"dilations": {JOINT:
factor}`` (optional), the pose shown in the page when the operation was made.
"""
from __future__ import annotations

import json
import math
from typing import NamedTuple, Union

import numpy as np

from ..errors import ProtocolError

#: the longest message text that is parsed (bytes of UTF-8); websockets closes on frames over its
#: own ``max_size`` before this is reached (server.MAX_FRAME)
MAX_MESSAGE = 16 * 1024
#: the longest string a message may hold (ids, clip and joint names)
MAX_STRING = 256
#: the most dilated joints one pose may name
MAX_DILATIONS = 512
#: the largest coordinate accepted (a blade or plane far beyond any model is a mistake, and the
#: squares the kernels take must stay finite)
MAX_COORDINATE = 1e12
#: dilation factors outside this range are refused (a joint scaled to nothing or to infinity)
DILATION_RANGE = (1e-3, 1e3)

OPS = ("hello", "tear", "cut", "drill", "undo", "save")


class PoseSpec(NamedTuple):
    """The pose a page showed: ``clip`` (None: the stored mesh), ``time`` in seconds, and
    ``dilations`` ((joint name, factor), ...) applied after the clip's pose."""

    clip: str | None
    time: float
    dilations: tuple


class Hello(NamedTuple):
    id: object


class Tear(NamedTuple):
    """scalpel_from, scalpel_to : (2, 3) float64, the blade (handle, tip) at the previous step and now."""

    id: object
    scalpel_from: np.ndarray
    scalpel_to: np.ndarray
    opening: float
    pose: PoseSpec


class Cut(NamedTuple):
    """normal, point : (3,) float64, the cutting plane."""

    id: object
    normal: np.ndarray
    point: np.ndarray
    cap: bool
    pose: PoseSpec


class Drill(NamedTuple):
    """start, end : (3,) float64, where the bit enters and where its tip stops; radius > 0."""

    id: object
    start: np.ndarray
    end: np.ndarray
    radius: float
    wall: bool
    pose: PoseSpec


class Undo(NamedTuple):
    id: object


class Save(NamedTuple):
    id: object


Request = Union[Hello, Tear, Cut, Drill, Undo, Save]

#: the fields each operation may hold, beside "op" and "id"
_POSE_FIELDS = {"clip", "time", "dilations"}
FIELDS = {"hello": set(), "undo": set(), "save": set(),
          "tear": {"from", "to", "opening"} | _POSE_FIELDS,
          "cut": {"normal", "point", "cap"} | _POSE_FIELDS,
          "drill": {"start", "end", "radius", "wall"} | _POSE_FIELDS}


def _reject_constant(name: str):
    # (json.loads accepts NaN, Infinity and -Infinity by default: they are not JSON)
    raise ValueError(f"{name} is not a JSON number")


def parse(text) -> Request:
    """The request that ``text`` (a JSON message as str or bytes) holds; ProtocolError otherwise."""
    if isinstance(text, (bytes, bytearray, memoryview)):
        raise ProtocolError("binary messages are not understood: send JSON text")
    if not isinstance(text, str):
        raise ProtocolError(f"a message must be JSON text, got {type(text).__name__}")
    if len(text) > MAX_MESSAGE or len(text.encode("utf-8", "surrogatepass")) > MAX_MESSAGE:
        raise ProtocolError(f"message of {len(text.encode('utf-8', 'surrogatepass'))} bytes: the limit is "
                            f"{MAX_MESSAGE} (a request holds a few numbers)")
    try:
        message = json.loads(text, parse_constant=_reject_constant)
    except RecursionError:
        raise ProtocolError("the message nests too deeply") from None
    except ValueError as exc:          # (json.JSONDecodeError, too long integers, NaN/Infinity)
        raise ProtocolError(f"not JSON: {exc}") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"a message must be a JSON object, got {type(message).__name__}")
    id = _id(message.get("id"))
    op = message.get("op")
    if op not in OPS:
        raise ProtocolError(f"op {_short(op)}: the operations are {', '.join(OPS)}", id)
    unknown = set(message) - FIELDS[op] - {"op", "id"}
    if unknown:
        raise ProtocolError(f"{op}: unknown field(s) {', '.join(sorted(_short(k) for k in unknown))}; "
                            f"it takes {', '.join(sorted(FIELDS[op])) or 'none'}", id)
    try:
        return _REQUESTS[op](id, message)
    except ProtocolError as exc:
        raise ProtocolError(f"{op}: {exc}", id) from None


def _id(value):
    """The message's id: None, an integer that JSON numbers hold exactly, or a short string."""
    if value is None or (isinstance(value, int) and not isinstance(value, bool) and abs(value) < 2 ** 53):
        return value
    if isinstance(value, str) and len(value) <= 64:
        return value
    raise ProtocolError(f"id {_short(value)}: give an integer or a string of at most 64 characters")


def _short(value) -> str:
    """``value`` for an error message, cut short (a hostile message may hold megabytes)."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def number(value, name: str) -> float:
    """A finite JSON number (not a boolean) within +-MAX_COORDINATE, as float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ProtocolError(f"{name} must be a number, got {_short(value)}")
    if isinstance(value, int) and abs(value) > MAX_COORDINATE:      # (float() overflows past 1e308)
        raise ProtocolError(f"{name} must be finite and within +-{MAX_COORDINATE:g}, got {_short(value)}")
    x = float(value)
    if not math.isfinite(x) or abs(x) > MAX_COORDINATE:
        raise ProtocolError(f"{name} must be finite and within +-{MAX_COORDINATE:g}, got {_short(value)}")
    return x


def points(value, shape: tuple, name: str) -> np.ndarray:
    """A nested list of numbers of exactly ``shape`` ((3,) or (2, 3)) as a new float64 array."""
    def walk(item, dims, where):
        if not isinstance(item, list) or len(item) != dims[0]:
            size = len(item) if isinstance(item, list) else None
            raise ProtocolError(f"{where} must be a list of {dims[0]} "
                                f"{'numbers' if len(dims) == 1 else 'lists'}, got "
                                f"{'a list of ' + str(size) if size is not None else _short(item)}")
        if len(dims) == 1:
            return [number(x, f"{where}[{i}]") for i, x in enumerate(item)]
        return [walk(x, dims[1:], f"{where}[{i}]") for i, x in enumerate(item)]

    return np.array(walk(value, shape, name), dtype=np.float64)


def flag(value, name: str, default: bool) -> bool:
    if value is None:
        return default
    if not isinstance(value, bool):
        raise ProtocolError(f"{name} must be true or false, got {_short(value)}")
    return value


def string(value, name: str) -> str:
    if not isinstance(value, str) or not 0 < len(value) <= MAX_STRING:
        raise ProtocolError(f"{name} must be a string of 1 to {MAX_STRING} characters, got {_short(value)}")
    return value


def pose_spec(message: dict) -> PoseSpec:
    clip = message.get("clip")
    clip = None if clip is None else string(clip, "clip")
    time = number(message.get("time", 0.0), "time")
    if time < 0:
        raise ProtocolError(f"time must be >= 0 seconds, got {time!r}")
    dilations = message.get("dilations")
    dilations = {} if dilations is None else dilations
    if not isinstance(dilations, dict):
        raise ProtocolError(f"dilations must be an object {{joint: factor}}, got {_short(dilations)}")
    if len(dilations) > MAX_DILATIONS:
        raise ProtocolError(f"dilations name {len(dilations)} joints; at most {MAX_DILATIONS}")
    pairs = []
    for joint, factor in dilations.items():
        factor = number(factor, f"dilations[{_short(joint)}]")
        if not DILATION_RANGE[0] <= factor <= DILATION_RANGE[1]:
            raise ProtocolError(f"dilations[{_short(joint)}] = {factor!r}: give a factor in "
                                f"[{DILATION_RANGE[0]:g}, {DILATION_RANGE[1]:g}]")
        pairs.append((string(joint, "a dilated joint's name"), factor))
    return PoseSpec(clip, time, tuple(pairs))


def _tear(id, m: dict) -> Tear:
    opening = number(m.get("opening", 0.0), "opening")
    if opening < 0:
        raise ProtocolError(f"opening must be >= 0, got {opening!r}")
    return Tear(id, points(m.get("from"), (2, 3), "from"), points(m.get("to"), (2, 3), "to"), opening, pose_spec(m))


def _cut(id, m: dict) -> Cut:
    return Cut(id, points(m.get("normal"), (3,), "normal"), points(m.get("point"), (3,), "point"),
               flag(m.get("cap"), "cap", False), pose_spec(m))


def _drill(id, m: dict) -> Drill:
    radius = number(m.get("radius"), "radius")
    if radius <= 0:
        raise ProtocolError(f"radius must be > 0, got {radius!r}")
    return Drill(id, points(m.get("start"), (3,), "start"), points(m.get("end"), (3,), "end"), radius,
                 flag(m.get("wall"), "wall", True), pose_spec(m))


_REQUESTS = {"hello": lambda id, m: Hello(id), "undo": lambda id, m: Undo(id), "save": lambda id, m: Save(id),
             "tear": _tear, "cut": _cut, "drill": _drill}


def reply(id, **fields) -> str:
    """A successful reply's text: ``{"id": id, "ok": true, ...fields}``."""
    return json.dumps({"id": id, "ok": True, **fields}, separators=(",", ":"), allow_nan=False)


def error_reply(id, error: str, kind: str) -> str:
    """A failed request's reply: ``{"id": id, "ok": false, "error": text, "kind": exception name}``."""
    return json.dumps({"id": id, "ok": False, "error": error, "kind": kind}, separators=(",", ":"))
