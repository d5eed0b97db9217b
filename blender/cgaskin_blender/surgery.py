"""One cgaskin operation on a Blender mesh object, from reading it to writing the result back, timed
by stage; and its revert.

The object's mesh is replaced by a new mesh (the old one is kept, with a fake user, until the next
operation on the object or a revert); a cut's second half becomes a copy of the object (same parent,
modifiers and vertex-group names) holding the other half.
"""
from __future__ import annotations

import time
import warnings
from typing import Callable, NamedTuple

import numpy as np

import bpy

import cgaskin

from .mesh_in import MeshIn, read_mesh, read_weights
from .mesh_out import add_shape_keys, new_mesh, result_weights, weld, write_weights
from .scene_rig import STATIC_BONE, Refusal, armature_modifier, screen_pose

#: custom properties of an operated object: the mesh it had before, the objects the operation made
PREVIOUS, MADE = "cgaskin_previous_mesh", "cgaskin_made_objects"


class Times(NamedTuple):
    """Seconds spent in each stage of one operation (``LAST`` holds the latest)."""

    weights_in: float       # reading the vertex groups (a loop over the vertices: no bulk read)
    geometry_in: float      # the mesh, the armature and the pose into cgaskin
    cgaskin: float          # the operation itself
    geometry_out: float     # the result's meshes (positions, faces, corner data, shape keys)
    weights_out: float      # filling the vertex groups

    def line(self) -> str:
        return (f"cgaskin {self.cgaskin * 1e3:.1f} ms; geometry in {self.geometry_in * 1e3:.1f} ms, out "
                f"{self.geometry_out * 1e3:.1f} ms; vertex groups in {self.weights_in * 1e3:.1f} ms, out "
                f"{self.weights_out * 1e3:.1f} ms")


class Scene(NamedTuple):
    """What an operation works on: the mesh in cgaskin, the pose on screen, world -> mesh space."""

    mesh: MeshIn
    pose: cgaskin.Pose
    to_mesh: np.ndarray     # (4, 4) the inverse of the object's world matrix


class Outcome(NamedTuple):
    """What an operation did."""

    times: Times
    notes: list             # warnings cgaskin gave, one line each
    objects: list           # the object, then any it made
    results: list           # cgaskin's rig for each of them (split vertices)
    welds: list             # mesh_out.Welded: each Blender vertex's row in its rig (``first``)
    source: MeshIn          # the object as read (its ``skin`` poses the results: ``screen_pose``)


#: the latest operation's Outcome (the panel shows its times; tests and benchmarks read it)
LAST: list = []


def operate(context, obj, run: Callable[[Scene], list]) -> Outcome:
    """Run ``run`` (Scene -> result rigs, the first for ``obj``, any others for copies of it) on
    ``obj`` in the pose on screen and write the results back.

    Raises
    ------
    cgaskin.CgaskinError
        Whatever cgaskin refuses (``scene_rig.Refusal`` included); nothing is changed then.
    """
    start = time.perf_counter()
    armature = armature_modifier(obj).object
    weights = read_weights(obj)
    read_w = time.perf_counter()
    mesh_in = read_mesh(obj, armature, weights)
    scene = Scene(mesh_in, screen_pose(mesh_in.skin, armature, context.evaluated_depsgraph_get()),
                  np.linalg.inv(np.array(obj.matrix_world, dtype=np.float64)))
    read_g = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", cgaskin.PlacementWarning)
        warnings.simplefilter("always", cgaskin.ModelWarning)
        warnings.simplefilter("always", cgaskin.OpenRimWarning)
        results = run(scene)
    _check_unweighted(results, mesh_in)
    ran = time.perf_counter()
    notes = [str(w.message).splitlines()[0] for w in caught if issubclass(w.category, Warning)]
    if mesh_in.dropped:
        notes.append(f"not carried to the result: {', '.join(mesh_in.dropped)}")
    if mesh_in.over_four:
        notes.append(f"{mesh_in.over_four} vertices had more than 4 bone weights: cgaskin kept the 4 largest")
    forget(obj)
    materials = list(obj.data.materials)
    objects, welds = [], []
    for k, rig in enumerate(results):
        target = obj if k == 0 else _copy_of(obj)
        welded = weld(rig)
        mesh = new_mesh(obj.data.name, rig, welded, mesh_in, materials)
        if k == 0:
            obj.data.use_fake_user = True
            obj[PREVIOUS] = obj.data.name
        target.data = mesh
        for name in mesh_in.group_names:        # (Blender keeps vertex-group names on the mesh)
            if name not in target.vertex_groups:
                target.vertex_groups.new(name=name)
        add_shape_keys(target, rig, welded, mesh_in)
        objects.append(target)
        welds.append(welded)
    wrote_g = time.perf_counter()
    for target, rig, welded in zip(objects, results, welds):
        write_weights(target, result_weights(rig, welded, mesh_in))
    obj[MADE] = [made.name for made in objects[1:]]
    done = time.perf_counter()
    times = Times(read_w - start, read_g - read_w, ran - read_g, wrote_g - ran, done - wrote_g)
    outcome = Outcome(times, notes, objects, results, welds, mesh_in)
    LAST[:] = [outcome]
    return outcome


def _check_unweighted(results: list, mesh_in: MeshIn) -> None:
    """Refuse a result with vertices made between a vertex no bone weighs and a weighted one: cgaskin
    blends them, Blender cannot (its Armature modifier divides by the bone weights' total, so a vertex
    either follows its bones or stays)."""
    if mesh_in.skin.bone_names[-1] != STATIC_BONE:
        return
    static = len(mesh_in.skin.bone_names) - 1
    for rig in results:
        share = np.where(rig.joints == static, rig.weights, 0.0).sum(axis=1)
        blended = np.count_nonzero((share > 1e-9) & (share < 1 - 1e-9))
        if blended:
            raise Refusal(f"the operation makes {blended} vertices between vertices no bone weighs and weighted "
                          "ones, which Blender cannot skin as cgaskin does: weight the vertices there")


def _copy_of(obj):
    copy = obj.copy()           # (parent, modifiers, vertex-group names; its data is replaced)
    copy.name = obj.name + ".cut"
    for collection in obj.users_collection:
        collection.objects.link(copy)
    for key in (PREVIOUS, MADE):
        if key in copy:
            del copy[key]
    return copy


def forget(obj) -> None:
    """Let the mesh kept for ``revert`` go (a new operation keeps only the latest)."""
    previous = bpy.data.meshes.get(obj.get(PREVIOUS, ""))
    if previous is not None:
        previous.use_fake_user = False
    for key in (PREVIOUS, MADE):
        if key in obj:
            del obj[key]


def revert(obj) -> bool:
    """Give ``obj`` back the mesh it had before its latest operation and remove the objects that
    operation made; False when there is nothing to revert."""
    previous = bpy.data.meshes.get(obj.get(PREVIOUS, ""))
    if previous is None:
        return False
    made = [bpy.data.objects.get(name) for name in obj.get(MADE, [])]
    current = obj.data
    obj.data = previous
    previous.use_fake_user = False
    for copy in made:
        if copy is not None:
            mesh = copy.data
            bpy.data.objects.remove(copy)
            if mesh.users == 0:
                bpy.data.meshes.remove(mesh)
    if current.users == 0:
        bpy.data.meshes.remove(current)
    for key in (PREVIOUS, MADE):
        del obj[key]
    return True


def to_mesh_point(scene: Scene, point) -> np.ndarray:
    return scene.to_mesh[:3, :3] @ np.asarray(point, dtype=np.float64) + scene.to_mesh[:3, 3]


def to_mesh_direction(scene: Scene, direction) -> np.ndarray:
    moved = scene.to_mesh[:3, :3] @ np.asarray(direction, dtype=np.float64)
    return moved / np.linalg.norm(moved)


def to_mesh_normal(scene: Scene, normal) -> np.ndarray:
    """A plane's normal in mesh space (normals move by the inverse transpose)."""
    moved = np.linalg.inv(scene.to_mesh[:3, :3]).T @ np.asarray(normal, dtype=np.float64)
    return moved / np.linalg.norm(moved)


def to_mesh_length(scene: Scene, length: float) -> float:
    return float(length) * float(np.cbrt(abs(np.linalg.det(scene.to_mesh[:3, :3]))))


def posed_diagonal(scene: Scene) -> float:
    """The diagonal of the box of the mesh as posed (mesh space)."""
    posed = cgaskin.skin(scene.mesh.rig, scene.pose)
    return float(np.linalg.norm(posed.max(axis=0) - posed.min(axis=0)))
