"""The sidebar panel (N panel, tab "cgaskin"): the three tools with their options, and revert."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, PointerProperty

from . import kernels, surgery


def _is_stroke(_, obj) -> bool:
    return obj.type in {"GREASEPENCIL", "CURVE"}


class CgaskinSettings(bpy.types.PropertyGroup):
    """The panel's choices, kept with the scene."""

    plane: PointerProperty(name="Plane", type=bpy.types.Object, description="Z axis: the cut's normal (none: the 3D cursor)")
    cap: BoolProperty(name="Caps", default=False)
    stroke: PointerProperty(name="Stroke", type=bpy.types.Object, poll=_is_stroke,
                            description="Grease Pencil object or curve drawn on the mesh")
    opening: FloatProperty(name="Opening", default=0.0, min=0.0)
    depth: FloatProperty(name="Blade depth", default=0.0, min=0.0, description="0: 2% of the mesh's size")
    bit: PointerProperty(name="Bit", type=bpy.types.Object, description="Z axis: the drill's travel (none: the 3D cursor)")
    radius: FloatProperty(name="Radius", default=0.05, min=0.0)
    drill_depth: FloatProperty(name="Depth", default=0.0, min=0.0, description="0: through the whole mesh")
    wall: BoolProperty(name="Wall", default=True)


class CGASKIN_PT_tools(bpy.types.Panel):
    bl_label = "cgaskin"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "cgaskin"

    def draw(self, context):
        settings = context.scene.cgaskin
        layout = self.layout
        box = layout.box()
        box.prop(settings, "plane")
        box.prop(settings, "cap")
        op = box.operator("cgaskin.cut", text="Cut")
        op.plane, op.cap = settings.plane.name if settings.plane else "", settings.cap
        box = layout.box()
        box.prop(settings, "stroke")
        box.prop(settings, "opening")
        box.prop(settings, "depth")
        op = box.operator("cgaskin.tear", text="Tear")
        op.stroke = settings.stroke.name if settings.stroke else ""
        op.opening, op.depth = settings.opening, settings.depth
        box = layout.box()
        box.prop(settings, "bit")
        box.prop(settings, "radius")
        box.prop(settings, "drill_depth")
        box.prop(settings, "wall")
        op = box.operator("cgaskin.drill", text="Drill")
        op.bit = settings.bit.name if settings.bit else ""
        op.radius, op.depth, op.wall = settings.radius, settings.drill_depth, settings.wall
        layout.operator("cgaskin.revert", text="Revert")
        if kernels.compiling():
            layout.label(text="compiling cgaskin's kernels (once)...")
        if surgery.LAST:
            layout.label(text=surgery.LAST[0].times.line())


CLASSES = (CgaskinSettings, CGASKIN_PT_tools)
