"""A Blender mesh read into a cgaskin ``Rig``, with what the operators carry through the surgery.

Blender keeps UVs, custom normals, materials and smooth flags per face corner; cgaskin carries data
per vertex. So a Blender vertex becomes one cgaskin vertex per distinct corner data (as a glTF
exporter splits along seams: cgaskin welds positions for its topology, so the surgery sees one
surface), and each copy carries its Blender vertex index (``VERTEX``) for ``mesh_out`` to weld the
copies back. Faces are the mesh's loop triangles.

Everything is read with ``foreach_get`` except vertex-group weights, which Blender exposes per vertex
only (``read_weights``, timed apart by the operators).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

import cgaskin

from .scene_rig import Skin, armature_skin

#: cgaskin attribute names of what the operators carry (``UV`` and ``SHAPE`` take a number; custom
#: normals under glTF's name, which cgaskin renormalises where it blends them and sets on caps and walls)
VERTEX, MATERIAL, SHARP, NORMAL, GROUPS, WEIGHT_SUM, TEAR = (
    "_BLENDER_VERTEX", "_MATERIAL", "_SHARP", "NORMAL", "_GROUPS", "_WEIGHT_SUM", "_TEAR")
UV, SHAPE = "_UV{}", "_SHAPE{}"
#: corners of a vertex whose custom normals differ less than this share a copy (Blender decodes a
#: vertex's custom normal for each of its corners with noise of about 3e-5)
NORMAL_TOLERANCE = 1e-3
#: below this total a vertex's bone weights do not move it in Blender's Armature modifier
NO_WEIGHT = 1e-4


class Weights(NamedTuple):
    """Every vertex-group weight of a mesh, one row per (vertex, group) pair."""

    vertex: np.ndarray      # (k,) int64
    group: np.ndarray       # (k,) int64, index into obj.vertex_groups
    weight: np.ndarray      # (k,) float64


class ShapeKey(NamedTuple):
    """A shape key's settings (its offsets travel as a SHAPE attribute)."""

    name: str
    value: float
    mute: bool
    slider_min: float
    slider_max: float
    vertex_group: str
    relative_key: str
    interpolation: str


class MeshIn(NamedTuple):
    """A mesh object as a cgaskin rig and what writing a result back needs."""

    rig: cgaskin.Rig
    skin: Skin
    group_names: list       # the object's vertex groups, in order
    other_groups: list      # indices of the groups carried as the GROUPS attribute (not deforming bones)
    uv_names: list
    shape_keys: list        # ShapeKey of each key block, the basis first (the others' offsets: SHAPE k)
    custom_normals: bool
    dropped: list           # the mesh's other attributes (colours, edge flags...), not carried
    over_four: int          # vertices that had more than four bone weights (the four largest kept)


def read_weights(obj) -> Weights:
    """All vertex-group weights of ``obj`` (a Python loop over the vertices: Blender has no bulk read)."""
    vertex, group, weight = [], [], []
    for v in obj.data.vertices:
        for element in v.groups:
            vertex.append(v.index)
            group.append(element.group)
            weight.append(element.weight)
    return Weights(np.array(vertex, dtype=np.int64), np.array(group, dtype=np.int64),
                   np.array(weight, dtype=np.float64))


def _vectors(collection, width: int, count: int) -> np.ndarray:
    """(count, width) float32 of the "vector" property of each item of a collection (per corner)."""
    values = np.empty(count * width, dtype=np.float32)
    collection.foreach_get("vector", values)
    return values.reshape(count, width)


def _face_attribute(mesh, name: str, dtype) -> np.ndarray:
    """(f,) values of a face attribute (zeros where the mesh has none)."""
    values = np.zeros(len(mesh.polygons), dtype=dtype)
    if name in mesh.attributes:
        mesh.attributes[name].data.foreach_get("value", values)
    return values


def _triangles(mesh):
    """(t, 3) corners, (t,) polygons of the triangles, (c,) vertex of each corner. Triangles and quads
    are read from the polygons (a quad split at its first corner); other polygons by Blender's
    loop triangles."""
    corner_vertex = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vertex)
    start = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", start)
    sizes = np.diff(np.r_[start, len(corner_vertex)]) if len(start) else start
    if np.all((sizes == 3) | (sizes == 4)):
        quads = np.flatnonzero(sizes == 4)
        corners = np.concatenate([start[:, None] + np.arange(3), _quads_second(start[quads])])
        polygon = np.r_[np.arange(len(start)), quads]
    else:
        mesh.calc_loop_triangles()
        tris = mesh.loop_triangles
        corners = np.empty(len(tris) * 3, dtype=np.int32)
        tris.foreach_get("loops", corners)
        polygon = np.empty(len(tris), dtype=np.int32)
        tris.foreach_get("polygon_index", polygon)
    return corners.reshape(-1, 3).astype(np.int64), polygon.astype(np.int64), corner_vertex.astype(np.int64)


def _quads_second(start: np.ndarray) -> np.ndarray:
    """(q, 3) the second triangle (corners 0, 2, 3) of quads starting at ``start``."""
    return start[:, None] + np.array([0, 2, 3])


def _bone_rows(weights: Weights, group_names: list, bone_names: list, n: int):
    """(joints (n, 4), bone weights (n, 4), sums (n,), how many vertices had more than four)."""
    bone_of_name = {name: k for k, name in enumerate(bone_names)}
    bone_of_group = np.array([bone_of_name.get(name, -1) for name in group_names] + [-1], dtype=np.int64)
    bone = bone_of_group[weights.group] if len(weights.group) else np.empty(0, dtype=np.int64)
    keep = (bone >= 0) & (weights.weight > 0)
    vertex, bone, weight = weights.vertex[keep], bone[keep], weights.weight[keep]
    order = np.lexsort((-weight, vertex))
    vertex, bone, weight = vertex[order], bone[order], weight[order]
    first = np.searchsorted(vertex, np.arange(n))
    rank = np.arange(len(vertex)) - first[vertex]
    sums = np.bincount(vertex, weights=weight, minlength=n)
    joints = np.zeros((n, 4), dtype=np.int64)
    rows = np.zeros((n, 4))
    top = rank < 4
    joints[vertex[top], rank[top]] = bone[top]
    rows[vertex[top], rank[top]] = weight[top]
    # (Blender divides by the vertex's total: the same rows, summing to 1)
    rows /= np.maximum(rows.sum(axis=1), 1e-300)[:, None]
    return joints, rows, sums, int(np.count_nonzero(np.bincount(vertex[rank >= 4], minlength=n)))


def _split(used: np.ndarray, corner_vertex: np.ndarray, columns: list, n: int):
    """One cgaskin vertex per distinct (Blender vertex, corner data) among the ``used`` corners:
    (the corner each cgaskin vertex is read from, the cgaskin vertex of each used corner).

    ``columns``: (values (c,), tolerance) per column of corner data. Most corners hold what the first
    corner of their vertex holds, within the tolerance: those share the vertex's first copy; only the
    others (along seams) are told apart, on their data rounded to the tolerance. (Column by column:
    numpy gathers and compares 1-D arrays several times faster than rows of a few columns.)"""
    vertex_of = corner_vertex[used]
    first = np.full(n, -1, dtype=np.int64)
    first[vertex_of[::-1]] = used[::-1]
    present = np.flatnonzero(first >= 0)
    primary = np.full(n, -1, dtype=np.int64)
    primary[present] = np.arange(len(present))
    split_of = primary[vertex_of]
    first_of_corner = first[vertex_of]
    differs = np.zeros(len(used), dtype=bool)
    for values, tolerance in columns:
        differs |= np.abs(values[used] - values[first_of_corner]) > tolerance
    odd = np.flatnonzero(differs)
    if not len(odd):
        return first[present], split_of
    key = np.ascontiguousarray(np.stack([vertex_of[odd].astype(np.float64)] + [
        np.round(values[used[odd]] / tolerance) if tolerance else values[used[odd]].astype(np.float64)
        for values, tolerance in columns], axis=1))
    _, index, inverse = np.unique(key.view(np.dtype((np.void, key.shape[1] * 8))).ravel(),
                                  return_index=True, return_inverse=True)
    split_of[odd] = len(present) + inverse.ravel()
    return np.r_[first[present], used[odd][index]], split_of


def read_mesh(obj, armature, weights: Weights) -> MeshIn:
    """``obj``'s mesh (the data, not the evaluated mesh) as a cgaskin rig in ``armature``'s skeleton."""
    mesh = obj.data
    n = len(mesh.vertices)
    group_names = [group.name for group in obj.vertex_groups]
    skin = armature_skin(obj, armature, static=False)
    joints, rows, sums, over_four = _bone_rows(weights, group_names, skin.bone_names, n)
    unweighted = sums <= NO_WEIGHT
    if unweighted.any():                    # (the static bone comes last: the others keep their index)
        skin = armature_skin(obj, armature, static=True)
        joints[unweighted] = len(skin.bone_names) - 1
        rows[unweighted] = [1.0, 0.0, 0.0, 0.0]
        sums[unweighted] = 0.0
    other = [k for k, name in enumerate(group_names) if name not in skin.bone_names]

    corners, polygon, corner_vertex = _triangles(mesh)
    n_corners = len(corner_vertex)
    per_corner = {}                         # attribute name -> (c, w) values of every corner
    uv_names = [layer.name for layer in mesh.uv_layers]
    for k, layer in enumerate(mesh.uv_layers):
        per_corner[UV.format(k)] = _vectors(layer.uv, 2, n_corners)
    custom = bool(mesh.has_custom_normals)
    if custom:
        per_corner[NORMAL] = _vectors(mesh.corner_normals, 3, n_corners)
    corner_polygon = np.zeros(n_corners, dtype=np.int64)
    corner_polygon[corners.ravel()] = np.repeat(polygon, 3)
    per_corner[MATERIAL] = _face_attribute(mesh, "material_index", np.int32)[corner_polygon][:, None].astype(np.float32)
    per_corner[SHARP] = _face_attribute(mesh, "sharp_face", bool)[corner_polygon][:, None].astype(np.float32)

    columns = [(np.ascontiguousarray(values[:, k]), NORMAL_TOLERANCE if name == NORMAL else 0.0)
               for name, values in per_corner.items() for k in range(values.shape[1])]
    source_corner, split_of = _split(corners.ravel(), corner_vertex, columns, n)
    source = corner_vertex[source_corner]
    faces = split_of.reshape(-1, 3)

    positions = np.empty(n * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", positions)
    positions = positions.reshape(n, 3).astype(np.float64)
    attributes = {VERTEX: source[:, None].astype(np.float64), WEIGHT_SUM: sums[source, None]}
    attributes.update({name: values[source_corner].astype(np.float64) for name, values in per_corner.items()})
    if other:
        dense = np.zeros((n, len(other)))
        column = np.full(len(group_names) + 1, -1)
        column[other] = np.arange(len(other))
        pick = column[weights.group] >= 0 if len(weights.group) else np.zeros(0, dtype=bool)
        dense[weights.vertex[pick], column[weights.group[pick]]] = weights.weight[pick]
        attributes[GROUPS] = dense[source]
    shape_keys = []
    if mesh.shape_keys is not None:
        for k, block in enumerate(mesh.shape_keys.key_blocks):
            if k:
                co = np.empty(n * 3, dtype=np.float32)
                block.data.foreach_get("co", co)
                attributes[SHAPE.format(k)] = (co.reshape(n, 3) - positions)[source]
            shape_keys.append(ShapeKey(block.name, block.value, block.mute, block.slider_min, block.slider_max,
                                       block.vertex_group, block.relative_key.name, block.interpolation))
    if TEAR in mesh.attributes and mesh.attributes[TEAR].domain == "POINT":
        tear = np.empty(n, dtype=np.float32)
        mesh.attributes[TEAR].data.foreach_get("value", tear)
        attributes[TEAR] = tear[source, None].astype(np.float64)
    rig = cgaskin.Rig(positions[source], faces, joints[source], rows[source], skin.skeleton,
                      attributes=attributes, name=obj.name)
    carried = {"position", "material_index", "sharp_face", "custom_normal", TEAR, *uv_names}
    dropped = [a.name for a in mesh.attributes if not a.name.startswith(".") and a.name not in carried]
    return MeshIn(rig, skin, group_names, other, uv_names, shape_keys, custom, dropped, over_four)
