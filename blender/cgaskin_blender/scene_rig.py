"""A Blender mesh object with an Armature modifier, as cgaskin sees it: the skeleton and the pose on
screen, in the mesh object's own space, and the checks for what cgaskin cannot reproduce exactly.

Blender's Armature modifier moves a vertex ``v`` (mesh coordinates) to
``P⁻¹ Σ w_i (pose_i · rest_i⁻¹) P v / Σ w_i``, where ``P`` is the mesh's transform relative to the
armature object (``armature.matrix_world⁻¹ · mesh.matrix_world``), ``pose_i`` the evaluated pose
bone's ``matrix`` and ``rest_i`` its bone's ``matrix_local`` (both in armature space). glTF skinning,
cgaskin's, is ``Σ w_i (G_i · IBM_i) v``. So the skeleton is built in mesh space: a root bone's rest
transform is ``P⁻¹ · rest``, every bone's inverse bind ``rest⁻¹ · P``, and the pose's global
transforms ``P⁻¹ · pose_i``. Vertices without any deforming weight stay where they are in Blender:
they are given to one extra bone that never moves (``STATIC_BONE``), which writes no vertex group.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

import cgaskin
from cgaskin.algebra.transforms import matrix_to_quat

#: the bone that holds vertices no deforming bone weighs (identity in every pose)
STATIC_BONE = "__cgaskin_static__"
#: how far a linear part may be from a multiple of a rotation (relative): Blender's matrices are float32
SIMILARITY_TOLERANCE = 1e-5


class Refusal(cgaskin.InvalidInputError):
    """What the object or its armature does that cgaskin cannot reproduce exactly (one line)."""


class Skin(NamedTuple):
    """The cgaskin skeleton of an armature, as seen from one mesh object."""

    skeleton: cgaskin.Skeleton
    bone_names: list        # the deforming bone of each cgaskin bone (STATIC_BONE for the last, if any)
    node_names: list        # the armature bone of each node, parents first
    mesh_from_armature: np.ndarray  # (4, 4) P⁻¹


def armature_modifier(obj):
    """The one Armature modifier that deforms ``obj``, after checking what cgaskin can reproduce.

    Raises
    ------
    Refusal
        A mesh without an Armature modifier (or with several), Preserve Volume, envelopes, a masking
        vertex group, Multi Modifier, an enabled modifier before it, shape keys that change the mesh.
    """
    if obj is None or obj.type != "MESH":
        raise Refusal("select a mesh object (the active object is "
                      f"{'nothing' if obj is None else repr(obj.name) + ', a ' + obj.type.lower()})")
    armatures = [m for m in obj.modifiers if m.type == "ARMATURE" and m.show_viewport]
    if len(armatures) != 1 or armatures[0].object is None or armatures[0].object.type != "ARMATURE":
        raise Refusal(f"{obj.name!r} needs one enabled Armature modifier with an armature object "
                      f"(it has {len(armatures)})")
    (modifier,) = armatures
    if modifier.use_deform_preserve_volume:
        raise Refusal(f"{modifier.name!r} uses Preserve Volume (dual quaternions): cgaskin skins linearly; "
                      "turn it off")
    if modifier.use_bone_envelopes or not modifier.use_vertex_groups:
        raise Refusal(f"{modifier.name!r} must bind to vertex groups only (no bone envelopes)")
    if modifier.vertex_group or modifier.use_multi_modifier:
        raise Refusal(f"{modifier.name!r} masks its effect (vertex group or Multi Modifier): clear it")
    before = [m.name for m in obj.modifiers[:list(obj.modifiers).index(modifier)] if m.show_viewport]
    if before:
        raise Refusal(f"modifiers before {modifier.name!r} change the mesh it deforms ({', '.join(before)}): "
                      "apply or disable them")
    keys = obj.data.shape_keys
    if keys is not None and keys.use_relative:
        active = [block.name for block in keys.key_blocks[1:]
                  if block.value != 0.0 and not block.mute and _moves(block)]
        if active:
            raise Refusal(f"shape keys {', '.join(active)} change the mesh before the armature: set them to 0")
    elif keys is not None:
        raise Refusal("absolute shape keys change the mesh before the armature: use relative keys")
    for bone in modifier.object.data.bones:
        if bone.use_deform and bone.bbone_segments > 1:
            raise Refusal(f"bone {bone.name!r} is a B-Bone ({bone.bbone_segments} segments): cgaskin deforms "
                          "by rigid bones; set its segments to 1")
    return modifier


def _moves(block) -> bool:
    """Whether a shape key's positions differ from those of the key it is relative to."""
    co = np.empty(len(block.data) * 3, dtype=np.float32)
    reference = np.empty_like(co)
    block.data.foreach_get("co", co)
    block.relative_key.data.foreach_get("co", reference)
    return not np.array_equal(co, reference)


def _matrices(items, attribute: str) -> np.ndarray:
    """(k, 4, 4) float64 of a matrix attribute of each item (Blender matrices, row-major)."""
    flat = np.empty(len(items) * 16, dtype=np.float32)
    items.foreach_get(attribute, flat)
    # (foreach_get gives each matrix column after column)
    return flat.reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)


def _similarity_scale(linear: np.ndarray) -> np.ndarray:
    """(k,) uniform scale of each (k, 3, 3) linear part, NaN where it is not a similarity."""
    det = np.linalg.det(linear)
    scale = np.cbrt(det)
    gram = np.swapaxes(linear, -1, -2) @ linear
    off = np.abs(gram - scale[:, None, None] ** 2 * np.eye(3)).max(axis=(1, 2))
    return np.where((det > 0) & (off <= SIMILARITY_TOLERANCE * np.maximum(scale ** 2, 1e-300)), scale, np.nan)


def mesh_from_armature(obj, armature) -> np.ndarray:
    """(4, 4) P⁻¹: armature space to the mesh object's space, checked to be a similarity."""
    relative = np.linalg.inv(np.array(armature.matrix_world, dtype=np.float64)) @ np.array(obj.matrix_world)
    if np.isnan(_similarity_scale(relative[None, :3, :3]))[0]:
        raise Refusal(f"{obj.name!r} is scaled non-uniformly (or mirrored) relative to {armature.name!r}: "
                      "apply its scale")
    return np.linalg.inv(relative)


def armature_skin(obj, armature, static: bool) -> Skin:
    """The cgaskin skeleton of ``armature`` in ``obj``'s space: every bone a node (parents first), the
    deforming bones its bones, and ``STATIC_BONE`` last when ``static``."""
    bones = armature.data.bones
    names = [bone.name for bone in bones]
    depth = np.array([len(bone.parent_recursive) for bone in bones])
    order = np.argsort(depth, kind="stable")
    node_names = [names[i] for i in order]
    node_of = {name: k for k, name in enumerate(node_names)}
    parents = np.array([node_of[bones[i].parent.name] if bones[i].parent else -1 for i in order], dtype=np.int64)
    to_mesh = mesh_from_armature(obj, armature)
    rest = to_mesh @ _matrices(bones, "matrix_local")[order]       # rest in mesh space, global
    local = rest.copy()
    has_parent = parents >= 0
    local[has_parent] = np.linalg.solve(rest[parents[has_parent]], rest[has_parent])
    deforming = [k for k in range(len(order)) if bones[int(order[k])].use_deform]
    bone_names = [node_names[k] for k in deforming]
    bone_nodes = list(deforming)
    inverse_bind = list(np.linalg.inv(rest[deforming]))
    if static:
        node_names.append(STATIC_BONE)
        parents = np.append(parents, -1)
        local = np.concatenate([local, np.eye(4)[None]])
        bone_names.append(STATIC_BONE)
        bone_nodes.append(len(node_names) - 1)
        inverse_bind.append(np.eye(4))
    scale = _similarity_scale(local[:, :3, :3])
    if np.isnan(scale).any():
        raise Refusal(f"the rest of {armature.name!r} is not rigid in {obj.name!r}'s space "
                      f"(bone {node_names[int(np.flatnonzero(np.isnan(scale))[0])]!r}): apply the scale")
    skeleton = cgaskin.Skeleton(node_names, parents, local[:, :3, 3], matrix_to_quat(local[:, :3, :3] / scale[:, None, None]),
                                np.repeat(scale[:, None], 3, axis=1), local, np.array(bone_nodes, dtype=np.int64),
                                np.array(inverse_bind))
    return Skin(skeleton, bone_names, node_names, to_mesh)


def screen_pose(skin: Skin, armature, depsgraph) -> cgaskin.Pose:
    """The pose on screen: the evaluated pose bones (constraints, IK, drivers), as a cgaskin pose.

    Raises
    ------
    Refusal
        A deforming bone scaled non-uniformly (or sheared by a parent that is).
    """
    evaluated = armature.evaluated_get(depsgraph)
    pose_bones = evaluated.pose.bones
    by_name = {name: k for k, name in enumerate(pose_bones.keys())}
    matrices = _matrices(pose_bones, "matrix")
    skeleton = skin.skeleton
    world = np.empty((skeleton.n_nodes, 4, 4))
    for k, name in enumerate(skin.node_names):
        world[k] = np.eye(4) if name == STATIC_BONE else skin.mesh_from_armature @ matrices[by_name[name]]
    deform = world[skeleton.bone_nodes] @ skeleton.inverse_bind
    bad = np.flatnonzero(np.isnan(_similarity_scale(deform[:, :3, :3])))
    if len(bad):
        raise Refusal(f"bone {skin.bone_names[int(bad[0])]!r} is scaled non-uniformly in this pose: cgaskin "
                      "reproduces uniform scale (dilation) only")
    local = world.copy()
    has_parent = skeleton.parents >= 0
    local[has_parent] = np.linalg.solve(world[skeleton.parents[has_parent]], world[has_parent])
    scale = _similarity_scale(local[:, :3, :3])
    # (a non-deforming bone may be scaled non-uniformly: kept as its exact matrix)
    rotation = np.where(np.isnan(scale)[:, None, None], np.eye(3), local[:, :3, :3] / np.nan_to_num(scale, nan=1.0)[:, None, None])
    exact = [local[k] if np.isnan(scale[k]) else None for k in range(len(local))]
    return cgaskin.Pose.from_trs(skeleton, local[:, :3, 3], matrix_to_quat(rotation),
                                 np.repeat(np.nan_to_num(scale, nan=1.0)[:, None], 3, axis=1), exact)
