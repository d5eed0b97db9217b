"""cgaskin inside Blender: cut, tear and drill a skinned mesh in the pose on screen, keeping its vertex
groups, UVs, custom normals, materials and shape keys, and its Armature modifier.

Operators ``cgaskin.cut``, ``cgaskin.tear``, ``cgaskin.drill``, ``cgaskin.revert``; the sidebar tab
"cgaskin" (``panel``). The geometry goes in and out through ``foreach_get``/``foreach_set``
(``mesh_in``, ``mesh_out``); ``scene_rig`` makes the armature and its evaluated pose cgaskin's.
"""
import bpy

from . import kernels, operators, panel

_CLASSES = kernels.CLASSES + operators.CLASSES + panel.CLASSES


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.cgaskin = bpy.props.PointerProperty(type=panel.CgaskinSettings)


def unregister():
    del bpy.types.Scene.cgaskin
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
