"""A cgaskin result written back as a Blender mesh: the split copies of each Blender vertex welded
again, the corner data (UVs, custom normals, material, smooth flag) put back on the face corners,
shape keys rebuilt from their carried offsets, the vertex groups filled.

Copies are welded when they came from the same Blender vertex (``VERTEX``: a new vertex on an edge
carries the same blend of its ends' indices in every copy), lie at the same rest position and are on
the same side of any slit (``TEAR``): the two sides of a tear stay apart even with no opening.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

import bpy

from .mesh_in import GROUPS, MATERIAL, NORMAL, SHAPE, SHARP, TEAR, UV, VERTEX, WEIGHT_SUM, MeshIn, Weights


class Welded(NamedTuple):
    """The Blender vertices of a result: each split vertex's welded vertex and one split vertex of each."""

    of_split: np.ndarray    # (n_split,) int64
    first: np.ndarray       # (n,) int64


def weld(rig) -> Welded:
    """Weld the split copies of ``rig`` (a cgaskin result of ``read_mesh``'s rig) back together."""
    columns = [rig.vertices, rig.attributes[VERTEX]]
    if TEAR in rig.attributes:
        columns.append(rig.attributes[TEAR])
    key = np.concatenate(columns, axis=1)
    order = np.lexsort(key.T[::-1])
    ordered = key[order]
    starts = np.r_[True, (ordered[1:] != ordered[:-1]).any(axis=1)]
    of_split = np.empty(len(key), dtype=np.int64)
    of_split[order] = np.cumsum(starts) - 1
    return Welded(of_split, order[starts])


def new_mesh(name: str, rig, welded: Welded, source: MeshIn, materials) -> bpy.types.Mesh:
    """A Blender mesh of ``rig``'s welded vertices and triangles, with its corner data and shape keys'
    offsets (the shape keys themselves need an object: ``add_shape_keys``)."""
    triangles = welded.of_split[rig.faces]
    whole = (triangles[:, 0] != triangles[:, 1]) & (triangles[:, 1] != triangles[:, 2]) & (triangles[:, 0] != triangles[:, 2])
    triangles, corner_split = triangles[whole], rig.faces[whole].ravel()
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(welded.first))
    mesh.vertices.foreach_set("co", rig.vertices[welded.first].astype(np.float32).ravel())
    mesh.loops.add(triangles.size)
    mesh.loops.foreach_set("vertex_index", triangles.astype(np.int32).ravel())
    mesh.polygons.add(len(triangles))
    mesh.polygons.foreach_set("loop_start", np.arange(0, triangles.size, 3, dtype=np.int32))
    first_corner = corner_split[::3]
    for material in materials:
        mesh.materials.append(material)
    # (face attributes written directly: ``Polygon.use_smooth`` is set one face at a time)
    mesh.attributes.new("material_index", "INT", "FACE").data.foreach_set(
        "value", np.rint(rig.attributes[MATERIAL][first_corner, 0]).astype(np.int32))
    mesh.attributes.new("sharp_face", "BOOLEAN", "FACE").data.foreach_set(
        "value", rig.attributes[SHARP][first_corner, 0] >= 0.5)
    for k, uv_name in enumerate(source.uv_names):
        layer = mesh.uv_layers.new(name=uv_name, do_init=False)
        layer.uv.foreach_set("vector", rig.attributes[UV.format(k)][corner_split].astype(np.float32).ravel())
    mesh.update(calc_edges=True)
    if source.custom_normals:
        normals = rig.attributes[NORMAL][corner_split]
        normals /= np.maximum(np.linalg.norm(normals, axis=1), 1e-30)[:, None]
        if bpy.app.version >= (4, 5, 0):     # free custom normals: one float vector per corner
            mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "CORNER").data.foreach_set(
                "vector", normals.astype(np.float32).ravel())
        else:
            mesh.normals_split_custom_set(normals)
    if TEAR in rig.attributes:
        labels = mesh.attributes.new(TEAR, "FLOAT", "POINT")
        labels.data.foreach_set("value", rig.attributes[TEAR][welded.first, 0].astype(np.float32))
    return mesh


def add_shape_keys(obj, rig, welded: Welded, source: MeshIn) -> None:
    """The shape keys of ``source`` on ``obj`` (whose mesh is new): positions from their carried
    offsets, then their settings (value, range, mute, vertex group, the key each is relative to)."""
    if not source.shape_keys:
        return
    rest = rig.vertices[welded.first]
    blocks = []
    for k, key in enumerate(source.shape_keys):
        block = obj.shape_key_add(name=key.name, from_mix=False)
        if k:
            block.data.foreach_set("co", (rest + rig.attributes[SHAPE.format(k)][welded.first]).astype(np.float32).ravel())
        blocks.append(block)
    for block, key in zip(blocks, source.shape_keys):
        block.slider_min, block.slider_max = key.slider_min, key.slider_max
        block.value, block.mute = key.value, key.mute
        block.vertex_group, block.interpolation = key.vertex_group, key.interpolation
        block.relative_key = obj.data.shape_keys.key_blocks[key.relative_key]


def result_weights(rig, welded: Welded, source: MeshIn) -> Weights:
    """The vertex-group weights of the result: cgaskin's bone weights (times the vertex's total as it
    was in Blender) and the carried weights of the other groups."""
    group_of_bone = np.array([source.group_names.index(name) if name in source.group_names else -1
                              for name in source.skin.bone_names], dtype=np.int64)
    joints = rig.joints[welded.first]
    weights = rig.weights[welded.first] * rig.attributes[WEIGHT_SUM][welded.first]
    vertex = np.repeat(np.arange(len(welded.first)), 4)
    group = group_of_bone[joints.ravel()]
    keep = (group >= 0) & (weights.ravel() > 0)
    vertex, group, weight = vertex[keep], group[keep], weights.ravel()[keep]
    if GROUPS in rig.attributes:
        dense = rig.attributes[GROUPS][welded.first]
        rows, columns = np.nonzero(dense > 0)
        vertex = np.concatenate([vertex, rows])
        group = np.concatenate([group, np.asarray(source.other_groups, dtype=np.int64)[columns]])
        weight = np.concatenate([weight, dense[rows, columns]])
    return Weights(vertex, group, weight)


def write_weights(obj, weights: Weights) -> int:
    """Fill ``obj``'s vertex groups (its mesh has none yet) with ``VertexGroup.add``, one call per
    group and distinct weight (Blender has no bulk write); returns the number of calls."""
    order = np.lexsort((weights.weight.astype(np.float32), weights.group))
    vertex, group = weights.vertex[order], weights.group[order]
    weight = weights.weight[order].astype(np.float32)
    starts = np.flatnonzero(np.r_[True, (group[1:] != group[:-1]) | (weight[1:] != weight[:-1])])
    ends = np.r_[starts[1:], len(vertex)]
    groups = obj.vertex_groups
    for start, end in zip(starts.tolist(), ends.tolist()):
        groups[int(group[start])].add(vertex[start:end].tolist(), float(weight[start]), "REPLACE")
    return len(starts)
