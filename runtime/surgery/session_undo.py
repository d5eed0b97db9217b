"""The records of an editing session's undo log (``session.py``): one record type, ``Undo``, for an
operation spliced in place (a stroke, a hole: the rows it rewrote) and for one that replaced the whole
mesh (a cut: the session's whole ``SessionState`` before it); and the log itself, ``History``, which
may be bounded in bytes (a server's tabs: a cut's record holds a whole mesh)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import InvalidInputError


class SessionState(NamedTuple):
    """Everything a session holds of its mesh (``Surgery._state``; a cut's ``Undo`` keeps it)."""

    template: object
    arrays: dict
    attributes: dict
    faces: object
    alive: object
    bvh: object
    influences: object
    used: object
    pad: object
    top_label: float
    labelled: bool
    bounds: np.ndarray


class Undo(NamedTuple):
    """What one operation changed, to take it back (the undo log's one record type). An operation
    spliced in place (a stroke, a hole): the counts before it and the old values of the rows it
    rewrote, ``removed`` the faces it took out and ``piece_parents`` (k,) the removed face each face it
    made (ids from ``m`` on) lies in (-1: none), whose BVH leaves take the removed faces back. An
    operation that replaced the whole mesh (a cut):
    ``replaced``, the session's whole state before it (``Undo.of_state``)."""

    n: int
    m: int
    rows: np.ndarray
    old_rows: dict
    moved: np.ndarray
    removed: np.ndarray
    piece_parents: np.ndarray
    kept: np.ndarray
    old_kept: np.ndarray
    moved_faces: np.ndarray
    boundary_rows: np.ndarray
    old_flags: np.ndarray
    scalars: tuple
    replaced: SessionState | None = None

    @classmethod
    def of_state(cls, state: SessionState) -> "Undo":
        none = np.empty(0, np.int64)
        return cls(0, 0, none, {}, none, none, none, none, none, none, none, none, (), state)


def held_bytes(value) -> int:
    """The bytes of the numpy buffers ``value`` holds (through tuples, lists, dicts and objects'
    attributes), each buffer once: views count as the array they view."""
    seen, total, stack = set(), 0, [value]
    while stack:
        item = stack.pop()
        if isinstance(item, np.ndarray):
            while isinstance(item.base, np.ndarray):
                item = item.base
            if id(item) not in seen:
                seen.add(id(item))
                total += item.nbytes
        elif isinstance(item, (tuple, list)):
            stack.extend(item)
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif hasattr(item, "__dict__") and id(item) not in seen:
            seen.add(id(item))
            stack.extend(vars(item).values())
    return total


class History:
    """The undo log: ``Undo`` records, the newest last. With ``max_bytes`` (None: no bound), a record
    that takes the log past it lets the oldest records go (they can no longer be undone; ``dropped``
    counts them); the newest record always stays."""

    def __init__(self, max_bytes: int | None = None):
        if max_bytes is not None and (isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 0):
            raise InvalidInputError(f"max_undo_bytes {max_bytes!r}: give a number of bytes >= 0, or None")
        self.max_bytes = max_bytes
        self.dropped = 0
        self._records: list = []
        self._sizes: list = []

    def append(self, record: Undo) -> None:
        self._records.append(record)
        self._sizes.append(held_bytes(record) if self.max_bytes is not None else 0)
        while self.max_bytes is not None and len(self._records) > 1 and sum(self._sizes) > self.max_bytes:
            del self._records[0], self._sizes[0]
            self.dropped += 1

    def pop(self) -> Undo:
        self._sizes.pop()
        return self._records.pop()

    @property
    def bytes(self) -> int:
        """What the records hold (0 when the log is unbounded: it is not measured then)."""
        return sum(self._sizes)

    def __len__(self) -> int:
        return len(self._records)
