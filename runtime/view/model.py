"""What the page shows of a rig: the rig as .glb bytes, the clip to start with, the open edges (cut
rims, slits, holes), and the page itself (``view_html``)."""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ..animation.pose import Pose, clip_from_poses
from .._shared.checks import real_number
from ..animation.rig import Rig
from ..errors import InvalidInputError
from ..rigs import load, save
from ..surgery.surface import tear_topology
from .page import page_html

#: the name of the clip that holds a pose given to ``view_html`` (a number is added if the rig has it)
POSE_CLIP = "pose"


def rim_edges(rig: Rig) -> np.ndarray:
    """The boundary edges of a rig's surface: the open edges the viewer draws.

    An edge is on the boundary when one face uses it, counted on the mesh welded by position (files
    split vertices along UV seams; those are no boundary) and by tear label (a closed slit's two sides
    coincide but are apart): so these are a cut's open rim, a slit's two lips, a hole's rim and any
    border the model had.

    Parameters
    ----------
    rig : Rig
        The model.

    Returns
    -------
    (b, 2) int64
        Each edge as the vertices of the one face that uses it, in the rig's vertex order.

    Examples
    --------
    >>> arm = cgaskin.capsule_arm()
    >>> hand, shoulder = cgaskin.cut(arm, [1, 0, 0], [1.55, 0, 0])
    >>> cgaskin.view.rim_edges(arm).shape, cgaskin.view.rim_edges(hand).shape      # closed; the cut's rim
    ((0, 2), (32, 2))
    """
    topology = tear_topology(rig)
    boundary = topology.boundary_edges
    first = topology.edge_face_offsets[boundary]
    face = topology.edge_face_faces[first]
    corner = topology.edge_face_corners[first].astype(np.int64)
    faces = np.asarray(rig.faces)
    return np.stack([faces[face, corner], faces[face, (corner + 1) % 3]], axis=1).astype(np.int64)


def rig_glb(rig: Rig) -> bytes:
    """``rig`` as ``cgaskin.save`` writes it to a .glb (through a temporary file: the exporter writes files)."""
    with tempfile.TemporaryDirectory(prefix="cgaskin-view-") as folder:
        path = Path(folder) / "model.glb"
        save(rig, path)
        return path.read_bytes()


def as_rig(model) -> Rig:
    """A ``Rig``, or a model path (anything ``cgaskin.load`` reads) loaded as one."""
    if isinstance(model, Rig):
        return model
    if isinstance(model, (str, Path)):
        return load(model)
    raise InvalidInputError(f"model must be a cgaskin.Rig or a model file path, got {type(model).__name__}")


def clip_name(rig: Rig, clip) -> str | None:
    """The name of ``clip`` (a name or an index of ``rig.clips``; None: the first clip, or None
    without clips); InvalidInputError naming the clips there are."""
    names = [c.name for c in rig.clips]
    if clip is None:
        return names[0] if names else None
    if isinstance(clip, (int, np.integer)) and not isinstance(clip, bool) and -len(names) <= clip < len(names):
        return names[clip]
    if isinstance(clip, str) and clip in names:
        return clip
    there = ", ".join(repr(n) for n in names) if names else "none (the model has no animation)"
    raise InvalidInputError(f"clip {clip!r}: the model has no such clip; its clips: {there}")


def _with_pose(rig: Rig, pose: Pose) -> tuple[Rig, str]:
    """``rig`` with a clip that holds ``pose`` (two equal keys, 0 s and 1 s: a clip of one key
    has no duration, which three.js cannot loop), and that clip's name."""
    if not isinstance(pose, Pose):
        raise InvalidInputError(f"pose must be a cgaskin.Pose (rig.rest_pose(), rig.pose(clip, t), "
                                f"and their edits), got {type(pose).__name__}")
    names = {c.name for c in rig.clips}
    name, k = POSE_CLIP, 1
    while name in names:
        k += 1
        name = f"{POSE_CLIP} {k}"
    try:
        clip = clip_from_poses(name, [0.0, 1.0], [pose, pose])
    except InvalidInputError as exc:
        raise InvalidInputError(f"pose: {exc}") from None
    return rig.with_clips(clip), name


def view_html(model, *, clip=None, pose=None, play=None, time: float = 0.0, skinning: str = "cgaskin") -> str:
    """The self-contained page that shows a model (what ``cgaskin view`` writes).

    Parameters
    ----------
    model : Rig or str or os.PathLike
        The model, or a model file.
    clip : str or int, optional
        The clip to start with (default: the first clip; the page can switch).
    pose : Pose, optional
        A pose of the rig to show instead (held by an extra still clip, "pose", selected and
        paused); not with ``clip``.
    play : bool, optional
        Start playing (default: True for a clip, False for a pose).
    time : float, optional
        Seconds into the clip to start at.
    skinning : {"cgaskin", "three"}, optional
        Who skins the mesh in the page first (it can switch): the bones' versors blended by the
        generated GLSL ES in the vertex shader, or three.js's bone matrices.

    Returns
    -------
    str
        The HTML page: three.js, the viewer and the model inside; it makes no request.

    Examples
    --------
    >>> page = cgaskin.view.view_html(cgaskin.capsule_arm(), clip="wave", play=False)
    >>> page.startswith("<!doctype html>"), "<title>capsule_arm: cgaskin view</title>" in page
    (True, True)
    """
    rig = as_rig(model)
    if pose is not None and clip is not None:
        raise InvalidInputError(f"give a pose or a clip, not both (clip={clip!r}): the page shows one "
                                f"first, and its clip menu switches between all")
    if real_number(time, "time") < 0:
        raise InvalidInputError(f"time {time!r}: give seconds >= 0")
    if pose is not None:
        rig, name = _with_pose(rig, pose)
        play = False if play is None else play
    else:
        name = clip_name(rig, clip)
        play = name is not None if play is None else play
    return page_html(rig_glb(rig), name=rig.name or "model", rims=rim_edges(rig).reshape(-1), clip=name,
                     play=bool(play), time=float(time), skinning=skinning)
