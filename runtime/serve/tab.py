"""One page's session in ``cgaskin serve``: its own ``Surgery`` on the model, what the page holds of
it (``delta.Mirror``), and the answer to each of its messages.

Every tab (every WebSocket connection) gets a ``Tab`` of its own, so tabs never see each other's
edits. ``handle`` never raises: a message that is not a valid request, or an operation that fails
(a scalpel that misses, a path the tear cannot follow, nothing to undo), gets an error reply and
leaves the session as it was (``Surgery``'s operations change nothing when they raise).
"""
from __future__ import annotations

import base64
import sys
import time
import traceback

from ..errors import CgaskinError, LimitError
from ..surgery.session import Surgery
from ..surgery.session_drill import predicted_session_drill
from ..view.model import rig_glb
from . import protocol
from .delta import Mirror, full_delta
from .limits import Limits
from .protocol import Cut, Drill, Hello, ProtocolError, Save, Tear, Undo


class Tab:
    """The session of one page: its own ``Surgery`` on the model, and the reply to each message.

    Parameters
    ----------
    rig : Rig
        The model (never modified).
    limits : Limits, optional
        What the tab's operations may make.

    Examples
    --------
    >>> import json
    >>> tab = cgaskin.serve.Tab(cgaskin.capsule_arm())
    >>> reply = json.loads(tab.handle('{"op": "cut", "id": 1, "normal": [1, 0, 0], "point": [1.55, 0, 0]}'))
    >>> reply["ok"], reply["delta"]["n_vertices"], reply["operations"]
    (True, 754, 1)
    """

    def __init__(self, rig, limits: Limits = Limits()):
        self.model, self.limits = rig, limits
        self.surgery = Surgery(rig, max_undo_bytes=limits.max_undo_bytes)
        self.mirror = Mirror(rig)
        self._mesh_bytes = None

    # ---- messages in, replies out ---------------------------------------------------------------------
    def handle(self, text) -> str:
        """The reply to one message; never raises (a bad request or a failed operation gets an
        error reply, and the session stays as it was).

        Parameters
        ----------
        text : str
            The message: a JSON request (``serve.protocol``).

        Returns
        -------
        str
            The reply, JSON text: ``ok``, and the delta of the mesh or the error and its kind.
        """
        id = None
        try:
            request = protocol.parse(text)
            id = request.id
            return self._run(request)
        except ProtocolError as exc:
            return protocol.error_reply(exc.id if id is None else id, str(exc), "ProtocolError")
        except CgaskinError as exc:
            return protocol.error_reply(id, str(exc), type(exc).__name__)
        except Exception as exc:            # (a bug: reported to the page and on stderr; the server goes on)
            traceback.print_exc(file=sys.stderr)
            return protocol.error_reply(id, f"internal error: {type(exc).__name__}: {exc}", "InternalError")

    def _run(self, request) -> str:
        if isinstance(request, Hello):
            return protocol.reply(request.id, **self.summary())
        if isinstance(request, Save):
            glb = rig_glb(self.surgery.rig)
            name = f"{self.model.name or 'model'}-edited.glb"
            return protocol.reply(request.id, name=name, bytes=len(glb), glb=base64.b64encode(glb).decode("ascii"))
        self._check_budget(request)
        start = time.perf_counter()
        if isinstance(request, Tear):
            self.surgery.tear(request.scalpel_from, request.scalpel_to, pose=self.pose(request.pose),
                              opening=request.opening)
        elif isinstance(request, Cut):
            self.surgery.cut(request.normal, request.point, pose=self.pose(request.pose), cap=request.cap)
        elif isinstance(request, Drill):
            self.surgery.drill(request.start, request.end, request.radius, pose=self.pose(request.pose),
                               wall=request.wall)
        elif isinstance(request, Undo):
            self.surgery.undo()
        else:                                # (parse returns only the types above)
            raise TypeError(f"no handler for {type(request).__name__}")
        seconds = time.perf_counter() - start
        delta = self.mirror.update(self.surgery.rig)
        return protocol.reply(request.id, delta=delta, seconds=round(seconds, 6),
                              operations=self.surgery.n_operations, undo_dropped=self.surgery.undo_dropped)

    def _check_budget(self, request) -> None:
        """Raise ``LimitError`` when ``request`` may make more than ``limits`` grant (before it runs)."""
        if isinstance(request, Undo):
            return
        have, cap = self.surgery.n_vertices, self.limits.max_vertices
        if have >= cap:
            raise LimitError(f"this tab's mesh holds {have} vertices, this server's limit is {cap}: undo, "
                             "or save the model and serve the saved file")
        if isinstance(request, Drill):
            new = predicted_session_drill(self.surgery, request.start, request.end, request.radius,
                                          pose=self.pose(request.pose), wall=request.wall)
            if new > self.limits.max_new_vertices:
                raise LimitError(f"this drill would make up to {new} new vertices (predicted before it runs), "
                                 f"this server's limit is {self.limits.max_new_vertices} an operation")

    # ---- helpers ------------------------------------------------------------------------------------
    def pose(self, spec):
        """The ``Pose`` a request's pose names. Joints are named as the model names them (the page maps
        three.js's bone names back: three.js sanitises names and may give two joints one).

        Parameters
        ----------
        spec : serve.protocol.PoseSpec
            A clip and time, and dilations of joints.

        Returns
        -------
        Pose or None
            None (the stored mesh) when it names no clip and no dilation.
        """
        if spec.clip is None and not spec.dilations:
            return None
        rig = self.model
        pose = rig.rest_pose() if spec.clip is None else rig.pose(spec.clip, spec.time)
        for joint, factor in spec.dilations:
            if joint not in rig.skeleton.names:
                raise ProtocolError(f"dilations: the model has no joint {joint!r}")
            pose = pose.dilate(joint, factor)
        return pose

    def mesh_bytes(self) -> int:
        """The size of the whole original mesh as one delta message: what a delta is compared with.

        Returns
        -------
        int
            Bytes of that message.
        """
        if self._mesh_bytes is None:
            self._mesh_bytes = len(protocol.reply(0, delta=full_delta(self.model), seconds=0.0, operations=0))
        return self._mesh_bytes

    def summary(self) -> dict:
        rig = self.surgery.rig
        return {"model": self.model.name or "model", "n_vertices": rig.n_vertices, "n_faces": rig.n_faces,
                "clips": [{"name": c.name, "duration": c.duration} for c in rig.clips],
                "joints": list(rig.skeleton.names), "operations": self.surgery.n_operations,
                "bone_joints": [rig.skeleton.names[k] for k in rig.skeleton.bone_nodes],
                "mesh_bytes": self.mesh_bytes(), "max_message": protocol.MAX_MESSAGE,
                "limits": self.limits._asdict()}

