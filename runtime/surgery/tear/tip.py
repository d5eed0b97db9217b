"""The tip of a slit, where the next stroke continues it (step 2 of a tear stroke, before the blade meets
the skin).

A slit ends at its tip, a vertex of the torn mesh (the last stroke's S_(i+1), kept single). A stroke that
continues the slit starts where the previous one ended; on a playing model the skin has moved since,
and its blade at t_i (the previous step's blade, or one aimed at where the tip was drawn) meets the skin
beside the tip, not on it: the stroke would start a slit of its own beside the old one. So a blade at
t_i that passes within ``reach`` of the tip in the stroke's pose -- max(opening, ``tol.tip_reach`` of
the diagonal) -- is moved, without turning, to pass through the tip: the stroke meets the skin there
(``locate._meet``: at the tip, a boundary vertex) and continues the slit from its tip, wherever the
pose carried it. (The page of ``cgaskin serve`` does the same with the previous hit's barycentric
coordinates; ``Surgery.continue_slit`` aims a blade at the tip itself.)
"""
import math

import numpy as np

from ..._shared.jit import helper
from ...generated.skinning import skin_blend


@helper
def _tip_position(source, tip):
    """(3,) where vertex ``tip`` of the source lies on its surface: its row of positions at rest, skinned
    by the source's bone maps in a pose (a posed source fills its positions only where a query reached)."""
    _, _, vertices, positions, _, _, joints, weights, affines, posed, _, _ = source
    out = np.empty((1, 3))
    if posed:
        skin_blend(vertices[tip:tip + 1], joints[tip:tip + 1], weights[tip:tip + 1], affines, out)
    else:
        for c in range(3):
            out[0, c] = positions[tip, c]
    return out[0]


@helper
def _onto_tip(source, blades, tip, reach, snap):
    """``blades`` (4, 3) (handle and tip at t_i, then at t_(i+1)), or a copy whose blade at t_i is moved
    to pass through the slit's tip: vertex ``tip`` of ``source`` (``records.StrokeSource`` as a tuple;
    -1: none), when the blade passes within ``reach`` of it, further than ``snap`` (closer, it meets the
    surface there already: ``locate._meet``)."""
    if tip < 0 or tip >= source[2].shape[0]:
        return blades
    p = _tip_position(source, tip)
    a, b = blades[0], blades[1]
    dd, t = 0.0, 0.0
    for c in range(3):
        dd += (b[c] - a[c]) ** 2
        t += (p[c] - a[c]) * (b[c] - a[c])
    t = min(max(t / dd, 0.0), 1.0) if dd > 0.0 else 0.0
    shift = np.empty(3)
    for c in range(3):
        shift[c] = p[c] - (a[c] + t * (b[c] - a[c]))
    distance = math.sqrt(shift[0] ** 2 + shift[1] ** 2 + shift[2] ** 2)
    if not (snap < distance <= reach):
        return blades
    moved = blades.copy()
    for r in range(2):
        for c in range(3):
            moved[r, c] += shift[c]
    return moved


# ---- from Python: a session's slit tip ---------------------------------------------------------------------
def tip_point(vertices, joints, weights, affines, tip: int) -> np.ndarray:
    """(3,) vertex ``tip`` of a rest mesh (``vertices`` (n, 3), ``joints``, ``weights`` (n, 4)) where the bone
    maps ``affines`` (B, 12) put it (None: at rest), as ``_tip_position`` and ``cgaskin.skin`` compute it."""
    if affines is None:
        return np.array(vertices[tip], np.float64)
    out = np.empty((1, 3))
    skin_blend(vertices[tip:tip + 1], joints[tip:tip + 1], weights[tip:tip + 1], affines, out)
    return out[0]


def blade_through(blade: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(2, 3) ``blade`` (handle, tip) moved, without turning, so that its point nearest ``point`` (3,) is
    ``point``."""
    a, b = blade
    d = b - a
    t = min(max(float((point - a) @ d) / float(d @ d), 0.0), 1.0)
    return blade + (point - (a + t * d))


class TipLog:
    """A session's slit tip (``tip``: a vertex, -1 none) and what it was before each operation the undo
    log holds (``history``, an ``session_undo.History``: it may let its oldest records go)."""

    def __init__(self, history, tip: int = -1):
        self.tip, self._history, self._before = tip, history, []

    def operated(self, before: int) -> None:
        """An operation entered the undo log; the tip before it was ``before`` (``tip`` is now its own)."""
        self._before.append(before)
        del self._before[:max(0, len(self._before) - len(self._history))]

    def undone(self) -> None:
        """The last operation was taken back: its tip before it is the tip again."""
        self.tip = self._before.pop() if self._before else -1
