"""The operators: cut, tear and drill the active mesh object in the pose on screen, and revert.

Each reports what cgaskin refuses as one line (no traceback) and changes nothing then.
"""
from __future__ import annotations

import numpy as np

import bpy
from bpy.props import BoolProperty, FloatProperty, FloatVectorProperty, StringProperty
from mathutils import Vector

import cgaskin

from . import kernels, surgery
from .strokes import stroke_points
from .scene_rig import Refusal


def _matrix_of(context, name: str, what: str) -> np.ndarray:
    """(4, 4) world matrix of the object ``name``, or of the 3D cursor when ``name`` is empty."""
    if not name:
        return np.array(context.scene.cursor.matrix, dtype=np.float64)
    obj = bpy.data.objects.get(name)
    if obj is None:
        raise Refusal(f"no object named {name!r} for the {what}")
    return np.array(obj.matrix_world, dtype=np.float64)


class _Operation:
    """What the three operators share: the active mesh, the run, the reports."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and context.mode == "OBJECT"

    def invoke(self, context, event):
        if not kernels.ready():                 # (first use where the kernels did not ship compiled)
            bpy.ops.cgaskin.prepare_kernels("INVOKE_DEFAULT")
            self.report({"INFO"}, "cgaskin compiles its kernels once, in the background: run the tool "
                        "again when the status bar says it is done")
            return {"CANCELLED"}
        return self.execute(context)

    def execute(self, context):
        try:
            outcome = surgery.operate(context, context.active_object, self.run)
        except cgaskin.CgaskinError as exc:
            self.report({"ERROR"}, str(exc).strip().splitlines()[0])
            return {"CANCELLED"}
        for note in outcome.notes:
            self.report({"WARNING"}, note)
        self.report({"INFO"}, f"{self.bl_label}: {outcome.times.line()}")
        return {"FINISHED"}


class CGASKIN_OT_cut(_Operation, bpy.types.Operator):
    """Cut the active skinned mesh by a plane (an object's Z axis, or the 3D cursor's) in the pose on
    screen; the far half becomes a copy of the object"""

    bl_idname = "cgaskin.cut"
    bl_label = "cgaskin cut"

    plane: StringProperty(name="Plane", description="Object whose Z axis is the plane's normal (empty: the 3D cursor)")
    cap: BoolProperty(name="Caps", description="Close both halves with planar caps", default=False)

    def run(self, scene):
        matrix = _matrix_of(bpy.context, self.plane, "cut plane")
        normal = surgery.to_mesh_normal(scene, matrix[:3, 2])
        point = surgery.to_mesh_point(scene, matrix[:3, 3])
        positive, negative = cgaskin.cut(scene.mesh.rig, normal, point, pose=scene.pose, cap=self.cap)
        if positive.n_faces == 0 or negative.n_faces == 0:
            raise Refusal("the plane does not cross the mesh in this pose")
        return [positive, negative]


class CGASKIN_OT_tear(_Operation, bpy.types.Operator):
    """Tear the active skinned mesh along a stroke (Grease Pencil or curve) drawn on it, the blade along
    a direction (the view's by default), in the pose on screen"""

    bl_idname = "cgaskin.tear"
    bl_label = "cgaskin tear"

    stroke: StringProperty(name="Stroke", description="Grease Pencil object or curve that holds the stroke")
    blade_direction: FloatVectorProperty(name="Blade", description="Direction the blade points (zero: into the view)",
                                         size=3, default=(0.0, 0.0, 0.0))
    depth: FloatProperty(name="Depth", description="How far the blade reaches each side of the stroke "
                         "(0: 2% of the posed mesh's size)", default=0.0, min=0.0)
    opening: FloatProperty(name="Opening", description="How far the slit's sides move apart", default=0.0, min=0.0)

    def invoke(self, context, event):
        view = context.region_data
        if not any(self.blade_direction) and view is not None and hasattr(view, "view_rotation"):
            self.blade_direction = view.view_rotation @ Vector((0.0, 0.0, -1.0))
        return super().invoke(context, event)

    def run(self, scene):
        if not any(self.blade_direction):
            raise Refusal("give the blade a direction (there is no view to take it from)")
        points = np.array([surgery.to_mesh_point(scene, p) for p in stroke_points(bpy.data.objects.get(self.stroke))])
        direction = surgery.to_mesh_direction(scene, self.blade_direction)
        reach = surgery.to_mesh_length(scene, self.depth) if self.depth > 0 else 0.02 * surgery.posed_diagonal(scene)
        blades = np.stack([points - reach * direction, points + reach * direction], axis=1)
        session = cgaskin.Surgery(scene.mesh.rig)
        for blade_from, blade_to in zip(blades[:-1], blades[1:]):
            session.tear(blade_from, blade_to, pose=scene.pose, opening=self.opening)
        return [session.rig]


class CGASKIN_OT_drill(_Operation, bpy.types.Operator):
    """Drill a hole in the active skinned mesh along an object's Z axis (or the 3D cursor's), in the
    pose on screen"""

    bl_idname = "cgaskin.drill"
    bl_label = "cgaskin drill"

    bit: StringProperty(name="Bit", description="Object at the hole's start whose Z axis the bit travels along "
                        "(empty: the 3D cursor)")
    radius: FloatProperty(name="Radius", description="The bit's radius", default=0.05, min=0.0)
    depth: FloatProperty(name="Depth", description="How far the bit travels (0: through the whole mesh)",
                         default=0.0, min=0.0)
    wall: BoolProperty(name="Wall", description="Line the hole with a wall, keeping a closed mesh closed", default=True)

    def run(self, scene):
        matrix = _matrix_of(bpy.context, self.bit, "drill bit")
        axis = matrix[:3, 2] / np.linalg.norm(matrix[:3, 2])
        start = surgery.to_mesh_point(scene, matrix[:3, 3])
        if self.depth > 0:
            end = surgery.to_mesh_point(scene, matrix[:3, 3] + axis * self.depth)
        else:
            end = start + surgery.to_mesh_direction(scene, axis) * surgery.posed_diagonal(scene) * 2
        radius = surgery.to_mesh_length(scene, self.radius)
        return [cgaskin.drill(scene.mesh.rig, start, end, radius, pose=scene.pose, wall=self.wall)]


class CGASKIN_OT_revert(bpy.types.Operator):
    """Give the active object back the mesh it had before its latest cgaskin operation (and remove a
    cut's other half)"""

    bl_idname = "cgaskin.revert"
    bl_label = "cgaskin revert"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and surgery.PREVIOUS in obj

    def execute(self, context):
        if not surgery.revert(context.active_object):
            self.report({"ERROR"}, "nothing to revert on this object")
            return {"CANCELLED"}
        return {"FINISHED"}


CLASSES = (CGASKIN_OT_cut, CGASKIN_OT_tear, CGASKIN_OT_drill, CGASKIN_OT_revert)
