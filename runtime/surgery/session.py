"""An editing session: many tears, cuts and holes on one model, each costing what it touches.

``cgaskin.tear(rig, ...)`` returns a new rig, and the next stroke on it builds that rig's BVH again: the
whole mesh per stroke. A ``Surgery`` keeps the mutable state across operations instead: the mesh in
arrays with spare capacity (``rows.Rows``; a stroke rewrites the few rows it changes and appends its
new ones: ``session_splice.py``), removed faces as tombstones (face ids stay stable), a ``DynamicBVH``
updated for the faces a stroke removes, adds and moves, per vertex whether it lies on a boundary of
the label-aware weld (all a stroke needs of the whole mesh's topology), and an undo log of the rows
each operation changed. The state is in rest space, and so is the BVH: a stroke in a pose poses only
what its blade reaches (``posed_bounds.py``, ``posed_source.py``).

A stroke is ``tear/splice.py`` run on the session as its source, exactly as the functional ``tear`` runs
it on a rig, so a session's mesh after k strokes is the functional chain's (tests check it). ``cut`` cuts
the whole mesh and keeps both halves, apart; ``drill`` works on the faces around the bit.
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from .._shared.cache import seed
from .._shared.memory import collection_paused, minor_page_faults, release_free_memory
from ..errors import InvalidInputError
from .cut import cut as cut_rig
from .drill.api import checked_wall, warned
from .drill.bit import bit as checked_bit
from .dynamic_bvh import DynamicBVH
from .bone_influences import weight_summary
from .posed_bounds import PosedScratch, no_posing
from .posed_source import PosedSource, SessionInfluences, bone_affines_of
from .rows import Rows
from .session_drill import session_drill
from .session_undo import History, SessionState, Undo
from .session_splice import SplicedRows
from .surface import TEAR_LABEL
from .tear.rig_source import RigSource, slit_tip
from .tear.splice import stroke_splice
from .tear.stroke import StrokeResult, check_blade, check_blades, check_ends, check_opening, check_path
from .tear.tip import TipLog, blade_through, tip_point

__all__ = ["Surgery", "OperationCost"]

class OperationCost(NamedTuple):
    """What a session's last operation cost (``Surgery.last_cost``).

    Parameters
    ----------
    operation : str
        "tear", "cut", "drill" or "undo".
    seconds : float
        Its wall-clock time.
    page_faults : int
        The process's minor page faults while it ran: the fresh memory pages it wrote, each a trip to
        the operating system (0 where the system does not count them).

    Examples
    --------
    >>> import cgaskin
    >>> surgery = cgaskin.Surgery(cgaskin.capsule_arm())
    >>> surgery.cut([1, 0, 0], [1.1, 0, 0])
    >>> surgery.last_cost.operation
    'cut'
    """

    operation: str
    seconds: float
    page_faults: int


class Surgery(SplicedRows):
    """An editing session: many strokes, cuts and holes on one model, each costing what it touches.

    Parameters
    ----------
    rig : Rig
        The model (never modified).
    pose : Pose, optional
        The pose operations happen in unless they name one (None: the stored vertices).
    max_undo_bytes : int, optional
        A bound on the undo log's memory (None: unbounded); past it the oldest operations can no longer
        be undone (``undo_dropped`` counts them).

    Notes
    -----
    What a stroke reads of the session (``vertices``, ``faces``, ``positions``, ``labels``,
    ``boundary``, ... : the source interface of ``tear/splice.py``) are views of its own buffers,
    valid until the next operation: read them, never write them (``rig`` is the copy to keep). The
    undo log holds, per stroke, the old labels and positions of the rows it changed and the old
    corners of the faces it changed.

    Examples
    --------
    >>> import cgaskin
    >>> rig = cgaskin.capsule_arm()
    >>> surgery = cgaskin.Surgery(rig)
    >>> blade = lambda x: ([x, 0.05, 1.0], [x, 0.05, 0.0])
    >>> stroke = surgery.tear(blade(1.0), blade(1.5))
    >>> surgery.n_operations, surgery.n_vertices > rig.n_vertices
    (1, True)
    >>> surgery.undo()
    >>> surgery.n_vertices == rig.n_vertices
    True
    """

    #: the source interface's posing (``posed_bounds.Posing``): the session's own surface is at rest
    posing = no_posing()
    affines = None

    def __init__(self, rig, pose=None, max_undo_bytes: int | None = None):
        self._history = History(max_undo_bytes)
        self._last_cost = None
        self._tips = TipLog(self._history)
        self._reset(rig)
        self._pose, self._affines = pose, None if pose is None else bone_affines_of(rig, pose)

    @property
    def last_cost(self):
        """The ``OperationCost`` of the last operation that succeeded (None before the first)."""
        return self._last_cost

    @contextmanager
    def _costed(self, operation: str):
        """Time ``operation`` and count its page faults into ``last_cost`` when it succeeds."""
        faults, start = minor_page_faults(), time.perf_counter()
        yield
        self._last_cost = OperationCost(operation, time.perf_counter() - start, minor_page_faults() - faults)

    @property
    def pose(self):
        """The pose the session's operations happen in unless they name one (None: the stored vertices)."""
        return self._pose

    # ---- state ----------------------------------------------------------------------------------
    def _reset(self, rig) -> None:
        source = RigSource(rig, None, None)                      # checks the rig
        # the BVH first, over the rig's arrays: its build's temporaries are gone before the arrays are
        # copied (a lower peak); it reads the session's copies from the end of this on
        self._bvh = DynamicBVH(source.positions, source.faces)
        release_free_memory()
        self._template = rig
        self._arrays = {"vertices": Rows(source.vertices), "joints": Rows(source.joints),
                        "weights": Rows(source.weights), "labels": Rows(source.labels),
                        "boundary": Rows(source.boundary)}
        self._attributes = {name: (Rows(values), tail) for name, (values, tail) in source.attributes.items()}
        self._faces, self._alive = Rows(source.faces), Rows(np.ones(len(source.faces), bool))
        self.top_label = source.top_label
        self._tips.tip = source.tip                 # (a rig a stroke made knows its slit's tip)
        self._influences, self._scratch = SessionInfluences(self._bvh, rig.skeleton.n_bones), PosedScratch()
        self._used = self._pad = None               # (what a posed stroke needs: made by the first one)
        self._labelled = TEAR_LABEL in rig.attributes
        self._set_bounds(np.stack([source.positions.min(axis=0), source.positions.max(axis=0)]))
        self._snapshot = None
        self._bvh.use(self.positions, self.faces)
        release_free_memory()          # the builds' temporaries (half a millisecond)

    def _state(self) -> SessionState:
        return SessionState(self._template, self._arrays, self._attributes, self._faces, self._alive, self._bvh,
                            self._influences, self._used, self._pad, self.top_label, self._labelled, self._bounds)

    def _restore(self, state: SessionState) -> None:
        (self._template, self._arrays, self._attributes, self._faces, self._alive, self._bvh, self._influences,
         self._used, self._pad, self.top_label, self._labelled, bounds) = state
        self._set_bounds(bounds)
        self._scratch.reset()                   # (what it posed was of the tree the cut made)

    # ---- the source interface of tear/splice.py -------------------------------------------------------
    vertices = property(lambda self: self._arrays["vertices"].view)
    joints = property(lambda self: self._arrays["joints"].view)
    weights = property(lambda self: self._arrays["weights"].view)
    labels = property(lambda self: self._arrays["labels"].view)
    boundary = property(lambda self: self._arrays["boundary"].view)
    faces = property(lambda self: self._faces.view)

    positions = vertices          # (the session's surface is its rest mesh; a posed stroke poses it)
    tip = property(lambda self: self._tips.tip, doc="the vertex at the tip of the last slit (-1: none; tear/tip.py)")

    @property
    def attributes(self) -> dict:
        return {name: (rows.view, tail) for name, (rows, tail) in self._attributes.items()}

    def _set_bounds(self, box) -> None:
        """(2, 3) the surface's bounding box, and its diagonal (read by every stroke) with it."""
        self._bounds = box
        self.diagonal = float(np.linalg.norm(box[1] - box[0]))

    @property
    def bvh_arrays(self) -> tuple:
        return self._bvh.arrays

    def check_hits(self, faces) -> None:
        """Nothing to check: the session's BVH is built and kept over its own arrays.

        Parameters
        ----------
        faces : (k,) int64
            The faces a blade hit (the source interface of ``tear/splice.py``).
        """

    # ---- operations -------------------------------------------------------------------------------
    def tear(self, scalpel_from, scalpel_to, pose=None, opening: float = 0.0) -> StrokeResult:
        """One scalpel stroke (as ``cgaskin.tear_stroke``: the same arguments but the rig, the same
        errors) in ``pose`` (None: the session's pose); the session keeps the torn mesh. A stroke in a
        pose skins only the vertices its blade reaches. A stroke that raises changes nothing. A blade at
        t_i that passes near the tip of the last slit starts there (``tear/tip.py``: within the opening,
        or a thousandth of the diagonal, of where the pose carried the tip): the stroke continues it.

        Parameters
        ----------
        scalpel_from, scalpel_to : (2, 3) float
            The blade (handle, tip) at the previous step and now.
        pose : Pose, optional
            The pose of the stroke (None: the session's pose).
        opening : float >= 0
            How far the slit's lips open.

        Returns
        -------
        StrokeResult
            The stroke's path (``cgaskin.tear_stroke``'s result, without the rig).
        """
        with self._costed("tear"):
            blades = check_blades(scalpel_from, scalpel_to)
            opening = check_opening(opening)
            source = self if pose is None and self._pose is None else self._posed(pose)
            splice = stroke_splice(source, blades, opening, check_ends, check_path)
            self._history.append(self._apply(splice))
            self._tips.operated(self.tip)
            self._tips.tip = slit_tip(splice.stroke)
            self._labelled = self._labelled or bool(splice.stroke["split"].any())
            self._snapshot = None
        return StrokeResult(**splice.stroke)

    def continue_slit(self, scalpel_to, pose=None, opening: float = 0.0) -> StrokeResult:
        """Continue the last slit from its tip, wherever ``pose`` carried it, to where ``scalpel_to`` meets
        the skin.

        The stroke's blade at t_i is ``scalpel_to`` moved, without turning, to pass through the tip in the
        stroke's pose (the page of ``cgaskin serve`` carries its previous hit with the skin the same way,
        by barycentric coordinates): a drag across a playing model continues one slit.

        Parameters
        ----------
        scalpel_to : (2, 3) float
            The blade (handle a, tip b) at the end of the stroke, in the pose's space.
        pose : Pose, optional
            The pose of the stroke (None: the session's pose).
        opening : float >= 0
            As ``tear``.

        Returns
        -------
        StrokeResult
            As ``tear``; ``points[0]`` is the tip (``split[0]``: the slit goes on through it).

        Raises
        ------
        InvalidInputError
            No slit to continue (no stroke yet; the last one ended on an existing opening; a cut since),
            a malformed ``scalpel_to``; and the errors of ``tear``.

        Examples
        --------
        >>> import cgaskin
        >>> rig = cgaskin.capsule_arm()
        >>> surgery = cgaskin.Surgery(rig)
        >>> blade = lambda x: ([x, 0.03, 1.0], [x, 0.03, 0.0])      # above the arm, down to its axis
        >>> first = surgery.tear(blade(1.0), blade(1.1))
        >>> strokes = [surgery.continue_slit(blade(x), pose=rig.pose("wave", t))   # while the arm waves
        ...            for x, t in [(1.2, 0.02), (1.3, 0.04), (1.4, 0.06)]]
        >>> [bool(stroke.split[0]) for stroke in strokes]             # each goes on from the last tip
        [True, True, True]
        """
        if self.tip < 0:
            raise InvalidInputError("no slit to continue: the session has no stroke whose slit ends inside the "
                                    "surface (none yet, the last one ended on an existing opening, or a cut since)")
        blade = check_blade(scalpel_to, "scalpel_to")
        affines = self._affines if pose is None else bone_affines_of(self._template, pose)
        point = tip_point(self.vertices, self.joints, self.weights, affines, self.tip)
        return self.tear(blade_through(blade, point), blade, pose=pose, opening=opening)

    def cut(self, normal, point, pose=None, cap: bool = False) -> None:
        """Cut the whole mesh with the plane through ``point`` with normal ``normal`` (``cgaskin.cut``
        in ``pose``, None: the session's pose); both halves stay in the session, apart (the negative
        half's tear labels are moved past the positive half's, so that the halves do not weld along the
        cut).

        Parameters
        ----------
        normal, point : (3,) float
            The cutting plane.
        pose : Pose, optional
            The pose of the cut (None: the session's pose).
        cap : bool
            Close each half's rim with a cap.
        """
        with self._costed("cut"):
            positive, negative = cut_rig(self.rig, normal, point, pose=self._pose if pose is None else pose,
                                         cap=cap)
            previous, tip = self._state(), self.tip
            self._reset(replace(_joined(positive, negative), name=self._template.name))
            self._history.append(Undo.of_state(previous))
            self._tips.operated(tip)

    def drill(self, start, end, radius, pose=None, wall: bool = True):
        """Drill a hole (``cgaskin.drill`` in ``pose``, None: the session's pose; the same arguments but
        the rig, the same errors) on the faces around the bit (``session_drill.py``); returns the
        ``DrillResult`` of that region (its ``rig`` the region drilled, ``replaced`` and ``sources`` in
        its numbering; ``rig`` of the session is the whole mesh). The session's mesh is the functional
        drill's, but for the rows inside the bit, which it keeps unused. A drill that raises changes
        nothing.

        Parameters
        ----------
        start, end : (3,) float
            Where the bit enters and where its round tip stops.
        radius : float
            The bit's radius.
        pose : Pose, optional
            The pose of the drill (None: the session's pose).
        wall : bool
            Wall the hole on the bit's surface.

        Returns
        -------
        DrillResult
            The drill of the region around the bit.
        """
        with self._costed("drill"), collection_paused():     # (Python containers: see _shared/memory.py)
            the_bit, wall = checked_bit(start, end, radius), checked_wall(wall)
            posed = None if pose is None and self._pose is None else self._posed(pose)
            result, splice = session_drill(self, the_bit, wall, posed)
            self._history.append(self._apply(splice))
            self._tips.operated(self.tip)             # (the rows stay: the slit's tip is where it was)
            self._snapshot = None
        return warned(result)

    def undo(self) -> None:
        """Take back the last operation (raises InvalidInputError when there is none)."""
        if not self._history:
            raise InvalidInputError("nothing to undo: the session has no operation left to take back")
        with self._costed("undo"), collection_paused():
            record = self._history.pop()
            if record.replaced is None:
                self._revert(record)
            else:
                self._restore(record.replaced)
            self._tips.undone()
            self._snapshot = None

    @property
    def n_operations(self) -> int:
        """The operations that ``undo`` can take back."""
        return len(self._history)

    @property
    def undo_dropped(self) -> int:
        """The operations that left the undo log to keep it within ``max_undo_bytes``."""
        return self._history.dropped

    @property
    def n_vertices(self) -> int:
        return self._arrays["vertices"].n

    @property
    def n_faces(self) -> int:
        return self._bvh.n_faces

    @property
    def rig(self):
        """The session's mesh now, as a Rig of its own arrays (a copy: later operations leave it as
        it is); the same object until the next operation."""
        if self._snapshot is None:
            n = self.n_vertices
            attributes = {name: rows.view.reshape((n,) + tail).copy() for name, (rows, tail) in
                          self._attributes.items()}
            if self._labelled:
                attributes[TEAR_LABEL] = self.labels[:, None].astype(np.float64)
            rig = self._template._with_checked_mesh(self.vertices.copy(), self.faces[self._alive.view],
                                           self.joints.copy(), self.weights.copy(), attributes)
            seed(rig, "tear.boundary", self.boundary.copy())
            seed(rig, "tear.top_label", self.top_label)
            seed(rig, "tear.tip", self.tip)
            self._snapshot = rig
        return self._snapshot

    def __repr__(self) -> str:
        return (f"Surgery({self._template.name!r}: {self.n_vertices} vertices, {self.n_faces} faces, "
                f"{self.n_operations} operations)")

    def _posed(self, pose) -> PosedSource:
        """The session in ``pose`` (None: its own), as a stroke's source."""
        affines = self._affines if pose is None else bone_affines_of(self._template, pose)
        if self._used is None:          # (the rows a stroke adds change neither: weight_summary)
            self._used, self._pad = weight_summary(self.joints, self.weights, self._template.skeleton.n_bones)
        influences = self._influences.influences(self.joints, self.weights)
        return PosedSource(self, affines, self._bvh.arrays, self._bvh.n_nodes, influences,
                           self._used, self._scratch, self._pad)


def _joined(positive, negative):
    """One rig holding both halves of a cut, apart: the negative half's vertices after the positive
    half's, its tear labels past the positive half's."""
    n = positive.n_vertices
    labels = [np.asarray(r.attributes.get(TEAR_LABEL, np.zeros((r.n_vertices, 1))), np.float64).reshape(-1, 1)
              for r in (positive, negative)]
    labels[1] = labels[1] + (labels[0].max(initial=0.0) + 1.0)
    attributes = {name: np.concatenate((np.asarray(values), np.asarray(negative.attributes[name])))
                  for name, values in positive.attributes.items() if name != TEAR_LABEL}
    attributes[TEAR_LABEL] = np.concatenate(labels)
    return positive._with_checked_mesh(np.concatenate((positive.vertices, negative.vertices)),
                              np.concatenate((positive.faces, np.asarray(negative.faces) + n)),
                              np.concatenate((positive.joints, negative.joints)),
                              np.concatenate((positive.weights, negative.weights)), attributes)
