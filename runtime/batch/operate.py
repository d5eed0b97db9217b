"""One item, on a worker: load the rig (once per process), pose it, draw the operation through the
posed mesh, save the result atomically, and return its manifest row.

What the worker draws (each from the item's own generator, ``Item.rng``):

* the pose edits: a dilation factor, a rotation angle (and axis when the spec gives none);
* cut: a plane through a random point of the posed surface (area-uniform) with a random normal;
* tear: one scalpel stroke of ``length`` (x the diagonal) from a random surface point along a random
  tangent direction, the blade standing along the surface normal, as long as the stroke each side;
* drill: a bit of ``radius`` entering at a random surface point along the inward normal, from twice
  its radius outside to ``depth`` inside (both x the diagonal);
* none: nothing (the posed rig as it is).

A draw that misses (the plane leaves one half empty, the blade misses the skin or its path is
blocked, the bit misses) is drawn again, up to ``ATTEMPTS`` times; the attempt that succeeded is in
the row's params. The saved rig's node (rest) transforms are the item's pose, so that a glTF viewer
shows it posed; its bind matrices and clips are the model's. ``item_row`` never raises: a failure is
a row with an ``error``.
"""
from __future__ import annotations

import json
import math
import time
import warnings
from collections import OrderedDict
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._shared.atomic import TEMPORARY, replaced
from ..animation.skeleton import Skeleton
from ..algebra.transforms import matrix_to_trs
from ..errors import InvalidInputError, MissesMeshError, TearPathError
from .items import UNREADABLE, Item, file_sha256

__all__ = ["Row", "item_row", "output_names", "ATTEMPTS", "TMP_SUFFIX"]

#: draws per item before a miss becomes the item's error
ATTEMPTS = 5
#: item files being written end so (``<name>.<pid>.tmp.glb``: ``atomic.replaced`` keeps the suffix that
#: ``save`` wants); a run removes any a killed run left
TMP_SUFFIX = TEMPORARY + ".glb"
#: rigs kept per worker process, least recently used dropped first
_CACHED_RIGS = 8
_RIGS: OrderedDict = OrderedDict()


class Row(NamedTuple):
    """One manifest row: an item and what making it gave.

    ``files``, ``vertices``, ``faces``, ``sha256`` hold one entry per output file (a cut: the
    positive half ``items/<id>.a.glb``, then ``items/<id>.b.glb``; else ``items/<id>.glb``).

    Parameters
    ----------
    id : str
        The item's id.
    model : str
        The model as the spec names it.
    pose : str
        "rest" or "<clip>@<time>".
    operation : str
        cut, tear, drill or none.
    params : str
        JSON text: the operation's parameters and the pose edits drawn.
    files : tuple of str
        Output files, relative to the batch folder; empty when ``error`` is set.
    vertices, faces : tuple of int
        Each output's vertex and face counts.
    seconds : float
        The time making the item took.
    sha256 : tuple of str
        Each output file's sha256.
    error : str or None
        Why the item failed (``"MissesMeshError: ..."``), None when it was made.
    computed : bool, optional
        False for a row kept from an earlier run.

    Examples
    --------
    >>> row = cgaskin.batch.Row("3a7b4b3a153b4529", "arm.glb", "wave@0.5", "none", "{}",
    ...                         ("items/3a7b4b3a153b4529.glb",), (690,), (1376,), 0.02, ("f933...",), None)
    >>> row.error is None, row.computed
    (True, True)
    """

    id: str
    model: str
    pose: str
    operation: str
    params: str
    files: tuple
    vertices: tuple
    faces: tuple
    seconds: float
    sha256: tuple
    error: str | None
    computed: bool = True


def output_names(item: Item) -> list:
    """The item's output files, relative to the batch folder."""
    if item.operation == "cut":
        return [f"items/{item.id}.a.glb", f"items/{item.id}.b.glb"]
    return [f"items/{item.id}.glb"]


def item_row(item: Item, out: str) -> Row:
    """Make ``item`` and write its files under the batch folder ``out``; its row (never raises)."""
    start = time.perf_counter()
    params = {"instance": item.instance}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rig, load_warnings = _rig(item.path, item.model_sha256)
            rigs = _make(item, rig, params)
        notes = load_warnings + sorted({f"{w.category.__name__}: {w.message}" for w in caught})
        if notes:
            params["warnings"] = notes
        files, counts, hashes = [], [], []
        for name, result in zip(output_names(item), rigs):
            hashes.append(_save_whole(result, Path(out) / name))
            files.append(name)
            counts.append((result.n_vertices, result.n_faces))
        return Row(item.id, item.model, item.pose_label, item.operation, _json(params), tuple(files),
                   tuple(c[0] for c in counts), tuple(c[1] for c in counts), time.perf_counter() - start,
                   tuple(hashes), None)
    except Exception as exc:         # a bad model, a miss after every attempt, a bug: the item's row
        message = f"{type(exc).__name__}: {exc}".splitlines()[0]
        return Row(item.id, item.model, item.pose_label, item.operation, _json(params), (), (), (),
                   time.perf_counter() - start, (), message)


def _json(params: dict) -> str:
    return json.dumps(params, sort_keys=True, separators=(",", ":"))


def _rig(path: str, sha: str) -> tuple:
    """(rig, load warnings) of the model file, loaded once per process per (path, content)."""
    key = (path, sha)
    if key in _RIGS:
        _RIGS.move_to_end(key)
        return _RIGS[key]
    if sha.startswith(UNREADABLE):
        raise InvalidInputError(f"{path}: cannot read the model ({sha[len(UNREADABLE):]})")
    from ..rigs import load
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rig = load(path)
    # (hashed after loading: a file replaced between the two is caught here, not saved under the old id)
    if file_sha256(path) != sha:
        raise InvalidInputError(f"{path} changed since the batch started (its sha256 differs): run it again")
    entry = (rig, sorted({f"{w.category.__name__}: {w.message}" for w in caught}))
    _RIGS[key] = entry
    while len(_RIGS) > _CACHED_RIGS:
        _RIGS.popitem(last=False)
    return entry


def _pose(item: Item, rig, rng, params: dict):
    """The item's pose (clip at time, or rest) with its edits drawn from ``rng``."""
    pose = rig.rest_pose() if item.clip is None else rig.pose(item.clip, item.time)
    drawn = []
    for edit in item.edits:
        low, high = edit.range
        value = float(rng.uniform(low, high))
        if edit.kind == "dilate":
            pose = pose.dilate(edit.joint, value)
            drawn.append({"kind": "dilate", "joint": edit.joint, "scale": value})
        else:
            axis = np.array(edit.axis, float) if edit.axis is not None else _unit(rng.normal(size=3))
            pose = pose.rotate(edit.joint, axis, math.radians(value))
            drawn.append({"kind": "rotate", "joint": edit.joint, "degrees": value,
                          "axis": _unit(axis).tolist()})
    params["pose"] = {"clip": item.clip, "time": item.time, "edits": drawn}
    return pose


def _unit(v: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(v)
    return v / norm if norm > 0 else np.array([0.0, 0.0, 1.0])


class _Surface(NamedTuple):
    """The posed surface: corners a, b, c (m, 3), centres (m, 3), unit normals (m, 3), face areas
    (m,), the bounding-box diagonal."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    centres: np.ndarray
    normals: np.ndarray
    areas: np.ndarray
    diagonal: float


def _surface(positions: np.ndarray, faces: np.ndarray) -> _Surface:
    a, b, c = positions[faces[:, 0]], positions[faces[:, 1]], positions[faces[:, 2]]
    cross = np.cross(b - a, c - a)
    double = np.linalg.norm(cross, axis=1)
    if not double.sum() > 0:
        raise InvalidInputError("the posed mesh has no face of non-zero area to draw an operation on")
    normals = cross / np.where(double > 0, double, 1.0)[:, None]
    used = positions[faces.reshape(-1)]
    return _Surface(a, b, c, (a + b + c) / 3, normals, double / 2, float(np.linalg.norm(used.max(axis=0) - used.min(axis=0))))


def _surface_point(surface: _Surface, rng) -> tuple:
    """A point drawn uniformly by area on the surface, and its face's unit normal (outward for
    counter-clockwise faces)."""
    f = int(rng.choice(len(surface.areas), p=surface.areas / surface.areas.sum()))
    r1, r2 = rng.random(2)
    s = math.sqrt(r1)
    point = surface.a[f] * (1 - s) + surface.b[f] * (s * (1 - r2)) + surface.c[f] * (s * r2)
    return point, surface.normals[f]


def _draw(value, rng) -> float:
    low, high = value
    return float(rng.uniform(low, high)) if high > low else float(low)


def _make(item: Item, rig, params: dict) -> list:
    """The item's output rigs (posed skeleton, named by the id), its drawn parameters in ``params``."""
    from ..animation.skinning import skin
    rng = item.rng()
    pose = _pose(item, rig, rng, params)
    op = {"kind": item.operation, **{k: list(v) if isinstance(v, tuple) else v for k, v in item.params}}
    params["operation"] = op
    skeleton = posed_skeleton(pose)
    if item.operation == "none":
        return [replace(rig, skeleton=skeleton, name=item.id)]
    surface = _surface(skin(rig, pose), rig.faces)
    params["diagonal"] = surface.diagonal
    options = dict(item.params)
    for attempt in range(1, ATTEMPTS + 1):
        drawn = {}
        try:
            results = _OPERATIONS[item.operation](rig, pose, surface, options, rng, drawn)
        except (MissesMeshError, TearPathError) as exc:
            miss = f"{type(exc).__name__}: {exc}"
            continue
        op["drawn"], params["attempt"] = drawn, attempt
        suffixes = [".a", ".b"] if len(results) == 2 else [""]
        return [replace(r, skeleton=skeleton, name=item.id + s) for r, s in zip(results, suffixes)]
    raise MissesMeshError(f"{ATTEMPTS} draws missed the mesh; the last: {miss}")


def _cut(rig, pose, surface, options, rng, drawn) -> list:
    from ..surgery.cut import PlaneMissesMeshWarning, cut
    point, _ = _surface_point(surface, rng)
    normal = _unit(rng.normal(size=3))
    drawn.update(point=point.tolist(), normal=normal.tolist())
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlaneMissesMeshWarning)
        try:
            halves = cut(rig, normal, point, pose=pose, cap=options["cap"])
        except PlaneMissesMeshWarning as exc:
            raise MissesMeshError(f"PlaneMissesMeshWarning: {exc}") from None
    if not all(h.n_faces for h in halves):
        raise MissesMeshError("the plane leaves one half without faces")
    return list(halves)


def _tear(rig, pose, surface, options, rng, drawn) -> list:
    from ..surgery.tear import tear
    point, normal = _surface_point(surface, rng)
    length = _draw(options["length"], rng) * surface.diagonal
    tangent = rng.normal(size=3)
    tangent = _unit(tangent - normal * (tangent @ normal))
    # the stroke ends on the face (its centre) nearest to where the tangent step lands, so that it
    # follows a surface that curves away under it (a thin limb); each blade stands along its face's
    # normal, handle outside, tip inside, as long as the stroke each side
    ahead = point + tangent * length
    f = int(np.argmin(np.einsum("ij,ij->i", *(2 * [surface.centres - ahead]))))
    end, end_normal = surface.centres[f], surface.normals[f]
    blade_from = np.array([point + normal * length, point - normal * length])
    blade_to = np.array([end + end_normal * length, end - end_normal * length])
    opening = _draw(options["opening"], rng) * surface.diagonal
    drawn.update(blade_from=blade_from.tolist(), blade_to=blade_to.tolist(), opening=opening)
    return [tear(rig, blade_from, blade_to, pose=pose, opening=opening)]


def _drill(rig, pose, surface, options, rng, drawn) -> list:
    from ..surgery.drill import drill
    point, normal = _surface_point(surface, rng)
    radius = _draw(options["radius"], rng) * surface.diagonal
    depth = _draw(options["depth"], rng) * surface.diagonal
    start, end = point + normal * (2 * radius), point - normal * depth
    drawn.update(start=start.tolist(), end=end.tolist(), radius=radius)
    return [drill(rig, start, end, radius, pose=pose, wall=options["wall"])]


_OPERATIONS = {"cut": _cut, "tear": _tear, "drill": _drill}


def posed_skeleton(pose) -> Skeleton:
    """``pose.skeleton`` with ``pose`` as its node (rest) transforms: the exact local matrices, and
    their TRS (``matrix_to_trs``) for the file's nodes."""
    sk = pose.skeleton
    trs = [matrix_to_trs(m) for m in pose.matrices]
    return Skeleton(list(sk.names), sk.parents, np.array([t[0] for t in trs]), np.array([t[1] for t in trs]),
                    np.array([t[2] for t in trs]), np.array(pose.matrices), sk.bone_nodes, sk.inverse_bind)


def _save_whole(rig, path: Path) -> str:
    """Save ``rig`` at ``path`` whole (``atomic.replaced``: a reader, or a run killed half-way, sees the
    whole file or none); returns the file's sha256."""
    from ..rigs import save
    with replaced(path) as temporary:
        save(rig, temporary)
        return file_sha256(temporary)
