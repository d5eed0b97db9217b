"""The records of an editing session's undo log (``session.py``): one record type, ``Undo``, for an
operation spliced in place (a stroke, a hole: the rows it rewrote) and for one that replaced the whole
mesh (a cut: the session's whole ``SessionState`` before it)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np


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
