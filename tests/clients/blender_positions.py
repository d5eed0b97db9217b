"""Run by tests/clients/test_blender.py in a Python that has bpy (Blender 5.0 as a module):

    python blender_positions.py JOBS.json OUT.npz

JOBS.json: [{"path": ..., "pose": [clip name, seconds] or null}, ...]. Each file is imported into an
empty scene with Blender's glTF importer (merge_vertices=False keeps the file's vertex order); OUT.npz
holds, per job i: "i/stored" the mesh's vertices as imported, "i/posed" the evaluated (skinned)
vertices at the pose's time, both in glTF axes, "i/_NAME" each application attribute, and "i/error"
when the import failed. Blender is Z-up: glTF (x, y, z) = Blender (x, -z, y) rotated back here.
"""
import json
import sys
import traceback

import bpy
import numpy as np


def _gltf_axes(obj, mesh) -> np.ndarray:
    """World positions of ``mesh`` (the data of ``obj``) in glTF's axes."""
    co = np.zeros(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    matrix = np.array(obj.matrix_world)
    world = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    return np.c_[world[:, 0], world[:, 2], -world[:, 1]]


def _attributes(mesh) -> dict:
    out = {}
    for attribute in mesh.attributes:
        if attribute.name.startswith("_") and attribute.domain == "POINT":
            key, width = {"FLOAT": ("value", 1), "FLOAT2": ("vector", 2), "FLOAT_VECTOR": ("vector", 3),
                          "FLOAT_COLOR": ("color", 4)}[attribute.data_type]
            values = np.zeros(len(attribute.data) * width)
            attribute.data.foreach_get(key, values)
            out[attribute.name] = values.reshape(-1, width)
    return out


def _import(job: dict, i: int, out: dict) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=job["path"], merge_vertices=False, disable_bone_shape=True)
    objects = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    if len(objects) != 1:
        raise RuntimeError(f"expected one mesh object, got {[obj.name for obj in objects]}")
    (obj,) = objects
    out[f"{i}/stored"] = _gltf_axes(obj, obj.data)
    for name, values in _attributes(obj.data).items():
        out[f"{i}/{name}"] = values
    if job["pose"] is not None:
        clip, seconds = job["pose"]
        armature = obj.find_armature()
        action = armature.animation_data.action  # the importer makes the file's first clip active
        if not action.name.startswith(clip):
            raise RuntimeError(f"the active action is {action.name!r}, not clip {clip!r}")
        scene = bpy.context.scene
        frame = seconds * scene.render.fps / scene.render.fps_base
        scene.frame_set(int(frame), subframe=frame - int(frame))
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        out[f"{i}/posed"] = _gltf_axes(evaluated, evaluated.to_mesh())
        evaluated.to_mesh_clear()


def main(jobs_path: str, out_path: str) -> None:
    with open(jobs_path, encoding="utf-8") as f:
        jobs = json.load(f)
    out = {}
    for i, job in enumerate(jobs):
        try:
            _import(job, i, out)
        except Exception as error:  # reported per file by the test, with Blender's own message
            lines = traceback.format_exception_only(type(error), error)
            out[f"{i}/error"] = np.array(" ".join(line.strip() for line in lines)[-2000:])
    np.savez(out_path, **out)


if __name__ == "__main__":
    main(*sys.argv[1:3])
