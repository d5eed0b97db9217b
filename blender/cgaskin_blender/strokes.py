"""A scalpel stroke drawn in Blender: the points of a Grease Pencil stroke (the Blender 4.3+ API) or of
a curve, in world space."""
from __future__ import annotations

import numpy as np

from .scene_rig import Refusal


def _grease_pencil_points(obj) -> np.ndarray:
    layer = obj.data.layers.active or (obj.data.layers[-1] if len(obj.data.layers) else None)
    frame = layer.current_frame() if layer is not None else None
    if frame is None or frame.drawing is None or len(frame.drawing.strokes) == 0:
        raise Refusal(f"{obj.name!r} has no stroke on its active layer at this frame")
    stroke = frame.drawing.strokes[-1]                 # the latest one drawn
    points = np.array([tuple(point.position) for point in stroke.points], dtype=np.float64)
    layer_matrix = getattr(layer, "matrix_local", None)     # (a layer's own transform, where it has one)
    return _homogeneous(points) @ (np.eye(4) if layer_matrix is None else np.array(layer_matrix, dtype=np.float64)).T


def _curve_points(obj) -> np.ndarray:
    if len(obj.data.splines) == 0:
        raise Refusal(f"{obj.name!r} has no spline")
    spline = obj.data.splines[-1]
    if spline.type == "BEZIER":
        co = np.empty(len(spline.bezier_points) * 3, dtype=np.float32)
        spline.bezier_points.foreach_get("co", co)
        return _homogeneous(co.reshape(-1, 3).astype(np.float64))
    co = np.empty(len(spline.points) * 4, dtype=np.float32)
    spline.points.foreach_get("co", co)
    return _homogeneous(co.reshape(-1, 4)[:, :3].astype(np.float64))


def _homogeneous(points: np.ndarray) -> np.ndarray:
    return np.c_[points, np.ones(len(points))]


def stroke_points(obj) -> np.ndarray:
    """(k, 3) world positions of the stroke ``obj`` holds (its last stroke or spline), consecutive
    repeats dropped.

    Raises
    ------
    Refusal
        Not a Grease Pencil or curve object, no stroke, fewer than two distinct points.
    """
    if obj is None:
        raise Refusal("choose a stroke: a Grease Pencil object or a curve drawn on the mesh")
    if obj.type == "GREASEPENCIL":
        local = _grease_pencil_points(obj)
    elif obj.type == "CURVE":
        local = _curve_points(obj)
    else:
        raise Refusal(f"{obj.name!r} is a {obj.type.lower()}: the stroke must be a Grease Pencil object or a curve")
    world = local @ np.array(obj.matrix_world, dtype=np.float64).T
    points = world[:, :3]
    moved = np.r_[True, np.linalg.norm(np.diff(points, axis=0), axis=1) > 0]
    points = points[moved]
    if len(points) < 2:
        raise Refusal(f"the stroke of {obj.name!r} needs at least two distinct points")
    return points
