"""Run by tests/blender/test_operators.py in a Python that has bpy (Blender 5.0 as a module):

    python operate.py JOBS.json OUT.json

Each job imports a model with Blender's own importer into an empty scene, animates its armature where
the file has no clip (keyed rotations, a uniform bone scale and a Damped Track constraint that follows
an animated empty: the evaluated pose is more than the keys), runs one extension operator at a posed
frame, then evaluates the depsgraph at other frames. OUT.json holds, per job, what the test asserts:
the largest distance between Blender's skinned result and ``cgaskin.skin`` of cgaskin's result in the
pose of Blender's evaluated bones (over the box diagonal), weight sums, closedness on welded positions,
what revert restored, and the operator's report when it refused.
"""
import json
import sys
import traceback
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "blender"))
import cgaskin_blender  # noqa: E402
from cgaskin_blender import mesh_in, scene_rig, surgery  # noqa: E402

cgaskin_blender.register()
import cgaskin  # noqa: E402


def load(job: dict):
    """The skinned mesh object of the job's model, imported into an empty scene."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    path = job["model"]
    if job.get("fbx_from"):                   # a binary FBX written by Blender's exporter (see the test)
        bpy.ops.import_scene.gltf(filepath=job["fbx_from"])
        bpy.ops.export_scene.fbx(filepath=path, add_leaf_bones=False, bake_anim=False)
        bpy.ops.wm.read_factory_settings(use_empty=True)
    if path.endswith(".fbx"):
        bpy.ops.import_scene.fbx(filepath=path)
    else:
        bpy.ops.import_scene.gltf(filepath=path)
    skinned = [o for o in bpy.context.scene.objects if o.type == "MESH" and o.find_armature() is not None]
    for other in [o for o in bpy.context.scene.objects if o.type == "MESH" and o not in skinned]:
        bpy.data.objects.remove(other)
    (obj,) = skinned
    bpy.context.view_layer.objects.active = obj
    if job.get("animate"):
        animate(obj.find_armature())
    return obj


def animate(armature) -> None:
    """Keys on three deforming bones (rotations, a uniform scale) and a Damped Track on a fourth that
    follows an empty moving through the scene."""
    bones = [b for b in armature.pose.bones if b.bone.use_deform and b.children][:4]
    for frame, angle in ((1, 0.0), (20, 0.5), (40, -0.4), (60, 0.8)):
        for k, bone in enumerate(bones[:3]):
            bone.rotation_mode = "XYZ"
            bone.rotation_euler = (angle * (k + 1) / 3, 0.3 * angle, -angle / 2)
            bone.keyframe_insert("rotation_euler", frame=frame)
        bones[1].scale = (1 + angle / 4,) * 3
        bones[1].keyframe_insert("scale", frame=frame)
    target = bpy.data.objects.new("track_target", None)
    bpy.context.scene.collection.objects.link(target)
    center = armature.matrix_world @ bones[3].head
    for frame, offset in ((1, (0.0, 0.0, 0.0)), (60, (0.3, 0.2, 0.1))):
        target.location = center + Vector(offset) * armature.dimensions.length + Vector((0.0, 0.0, 0.5)) * armature.dimensions.length
        target.keyframe_insert("location", frame=frame)
    constraint = bones[3].constraints.new("DAMPED_TRACK")
    constraint.target = target


def evaluated_positions(obj) -> np.ndarray:
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3).astype(np.float64)


def surface_line(obj, job: dict) -> tuple:
    """(k, 3) points on the posed surface along a line across the model's middle, seen along the view
    direction (world), and that direction."""
    view = Vector(job.get("view", (0.0, 1.0, 0.0))).normalized()
    posed = evaluated_positions(obj) @ np.array(obj.matrix_world)[:3, :3].T + np.array(obj.matrix_world)[:3, 3]
    lo, hi = posed.min(axis=0), posed.max(axis=0)
    center, size = Vector((lo + hi) / 2), float(np.linalg.norm(hi - lo))
    across = Vector(job.get("across", (1.0, 0.0, 0.0))).normalized()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for s in np.linspace(job.get("from", -0.08), job.get("to", 0.08), job.get("points", 9)):
        origin = center + Vector(job.get("shift", (0.0, 0.0, 0.0))) * size + across * (s * size) - view * size
        hit, location, *_ , hit_object, _ = bpy.context.scene.ray_cast(depsgraph, origin, view)
        if hit and hit_object.name == obj.name:
            points.append(tuple(location))
    return np.array(points), tuple(view)


def curve_through(name: str, points: np.ndarray):
    curve = bpy.data.curves.new(name, "CURVE")
    spline = curve.splines.new("POLY")
    spline.points.add(len(points) - 1)
    spline.points.foreach_set("co", np.c_[points, np.ones(len(points))].astype(np.float32).ravel())
    obj = bpy.data.objects.new(name, curve)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def grease_pencil_through(name: str, points: np.ndarray):
    data = bpy.data.grease_pencils.new(name)
    layer = data.layers.new("stroke")
    frame = layer.frames.new(bpy.context.scene.frame_current)
    frame.drawing.add_strokes([len(points)])
    for point, position in zip(frame.drawing.strokes[0].points, points):
        point.position = tuple(position)
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def bit_empty(obj, job: dict):
    """An empty outside the posed model whose Z axis points through its middle."""
    posed = evaluated_positions(obj) @ np.array(obj.matrix_world)[:3, :3].T + np.array(obj.matrix_world)[:3, 3]
    lo, hi = posed.min(axis=0), posed.max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    view = Vector(job.get("view", (0.0, 1.0, 0.0))).normalized()
    empty = bpy.data.objects.new("bit", None)
    empty.location = Vector((lo + hi) / 2) + Vector(job.get("shift", (0.0, 0.0, 0.0))) * size - view * size
    empty.rotation_euler = view.to_track_quat("Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(empty)
    return empty, size


def _open_edges(obj) -> np.ndarray:
    """(k, 2) the edges not shared by exactly two triangles, on positions welded where equal (rest)."""
    mesh = obj.data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    _, welded = np.unique(co.reshape(-1, 3), axis=0, return_inverse=True)
    mesh.calc_loop_triangles()
    tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    tris = welded.ravel()[tris.reshape(-1, 3)]
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return unique[counts != 2]


def open_edges(obj) -> int:
    return len(_open_edges(obj))


def boundary_loops(obj) -> int:
    """Connected pieces of the open edges: one per slit."""
    parent = {}

    def find(a):
        while parent.setdefault(a, a) != a:
            a = parent[a]
        return a
    for a, b in _open_edges(obj).tolist():
        parent[find(a)] = find(b)
    return len({find(a) for a in parent})


def shape_offsets(obj) -> list:
    """Per shape key after the basis: the smallest and largest offset from the basis, per axis."""
    keys = obj.data.shape_keys
    if keys is None:
        return []
    n = len(obj.data.vertices)
    basis = np.empty(n * 3, dtype=np.float32)
    keys.key_blocks[0].data.foreach_get("co", basis)
    out = []
    for block in keys.key_blocks[1:]:
        co = np.empty(n * 3, dtype=np.float32)
        block.data.foreach_get("co", co)
        offset = (co - basis).reshape(-1, 3)
        out.append([offset.min(axis=0).tolist(), offset.max(axis=0).tolist()])
    return out


def group_sums(obj) -> np.ndarray:
    weights = mesh_in.read_weights(obj)
    return np.bincount(weights.vertex, weights=weights.weight, minlength=len(obj.data.vertices))


def mesh_state(obj) -> dict:
    mesh = obj.data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    weights = mesh_in.read_weights(obj)
    return {"co": co, "n_polygons": len(mesh.polygons), "weights": np.c_[weights.vertex, weights.group, weights.weight],
            "uv": [layer.name for layer in mesh.uv_layers], "materials": [m.name if m else None for m in mesh.materials]}


def operate(obj, job: dict, out: dict) -> dict:
    """Run the job's operator on ``obj``; its keyword arguments."""
    operation, options = job["operation"], dict(job.get("options", {}))
    if operation == "cut":
        empty, _ = bit_empty(obj, {**job, "shift": job.get("shift", (0.0, 0.0, 0.0))})
        empty.location += Vector(job.get("view", (0.0, 1.0, 0.0))).normalized() * obj.dimensions.length
        empty.rotation_euler = Vector(job.get("normal", (1.0, 0.2, 0.1))).normalized().to_track_quat("Z", "Y").to_euler()
        options["plane"] = empty.name
        if job.get("cursor"):                 # the same plane given by the 3D cursor
            bpy.context.scene.cursor.matrix = empty.matrix_world
            options["plane"] = ""
    elif operation in ("tear", "tear_gp"):
        points, view = surface_line(obj, job)
        out["stroke_points"] = len(points)
        maker = curve_through if operation == "tear" else grease_pencil_through
        options.update(stroke=maker("stroke", points).name, blade_direction=view)
        if job.get("no_direction"):           # headless there is no view to take it from
            del options["blade_direction"]
        operation = "tear"
    elif operation == "drill":
        empty, size = bit_empty(obj, job)
        options.update(bit=empty.name, radius=job["radius"] * size)
        if "depth" in job:                    # (the bit starts a size away from the middle)
            options["depth"] = job["depth"] * size
    return {"operation": operation, **options}


def run_job(job: dict) -> dict:
    out = {}
    obj = load(job)
    scene = bpy.context.scene
    for key, value in job.get("set", {}).items():        # a setting the operators must refuse
        exec(value, {"obj": obj, "bpy": bpy, "scene": scene, "Vector": Vector})
    scene.frame_set(job["frame"])
    before = mesh_state(obj)
    out["shape_keys_before"] = [b.name for b in obj.data.shape_keys.key_blocks] if obj.data.shape_keys else []
    out["custom_normals_before"] = obj.data.has_custom_normals
    out["sums_before"] = [float(s.min()), float(s.max())] if len(s := group_sums(obj)) else [0, 0]
    out["open_before"] = open_edges(obj)
    call = operate(obj, job, out)
    operation = call.pop("operation")
    if job.get("undo"):                       # (headless, Blender starts its undo system only when asked)
        bpy.ops.ed.undo_push(message="before cgaskin")
    try:
        result = getattr(bpy.ops.cgaskin, operation)(**call)
    except RuntimeError as exc:               # an operator's ERROR report, in background mode
        out["refused"] = str(exc)
        out["unchanged"] = bool(np.array_equal(mesh_state(obj)["co"], before["co"]))
        return out
    out["result"] = sorted(result)
    outcome = surgery.LAST[0]
    out["times"] = outcome.times._asdict()
    out["notes"] = outcome.notes
    out["objects"] = [o.name for o in outcome.objects]
    out["vertices"] = [len(o.data.vertices) for o in outcome.objects]
    out["faces"] = [len(o.data.polygons) for o in outcome.objects]
    out["input_vertices"] = len(before["co"]) // 3
    armature = obj.find_armature()
    errors, diagonal = [], None
    for frame in [job["frame"]] + job["check_frames"]:
        scene.frame_set(frame)
        pose = scene_rig.screen_pose(outcome.source.skin, armature, bpy.context.evaluated_depsgraph_get())
        for target, rig, welded in zip(outcome.objects, outcome.results, outcome.welds):
            blender = evaluated_positions(target)
            ours = cgaskin.skin(rig, pose)[welded.first]
            if diagonal is None:
                diagonal = float(np.linalg.norm(blender.max(axis=0) - blender.min(axis=0)))
            errors.append([frame, target.name, float(np.abs(blender - ours).max() / diagonal)])
    out["errors"] = errors
    scene.frame_set(job["frame"])
    sums = np.concatenate([group_sums(o) for o in outcome.objects])
    out["sums_after"] = [float(sums.min()), float(sums.max())]
    out["groups_same"] = all([g.name for g in o.vertex_groups] == [g.name for g in obj.vertex_groups]
                             for o in outcome.objects) and len(obj.vertex_groups) > 0
    out["uv_after"] = [[layer.name for layer in o.data.uv_layers] for o in outcome.objects]
    out["uv_before"] = before["uv"]
    out["materials_same"] = all([m.name if m else None for m in o.data.materials] == before["materials"]
                                for o in outcome.objects)
    out["modifiers"] = [[(m.type, m.object.name if getattr(m, "object", None) else None) for m in o.modifiers]
                        for o in outcome.objects]
    out["parents"] = [o.parent.name if o.parent else None for o in outcome.objects]
    out["open_after"] = [open_edges(o) for o in outcome.objects]
    out["shape_keys"] = [[b.name for b in o.data.shape_keys.key_blocks] if o.data.shape_keys else [] for o in outcome.objects]
    out["shape_key_values"] = [[b.value for b in o.data.shape_keys.key_blocks] if o.data.shape_keys else []
                               for o in outcome.objects]
    out["shape_offsets"] = [shape_offsets(o) for o in outcome.objects]
    out["custom_normals"] = [o.data.has_custom_normals for o in outcome.objects]
    out["material_faces"] = [np.bincount([p.material_index for p in o.data.polygons], minlength=2).tolist()
                             for o in outcome.objects]
    if job.get("continue"):                   # a second stroke from where the first ended
        first = out["vertices"][0]
        points, view = surface_line(obj, {**job, **job["continue"]})
        stroke = curve_through("stroke2", points)
        out["loops_before_continuing"] = boundary_loops(obj)
        bpy.ops.cgaskin.tear(stroke=stroke.name, blade_direction=view, **job.get("options", {}))
        out["continued_vertices"] = len(obj.data.vertices) - first
        out["loops_after_continuing"] = boundary_loops(obj)
    if job.get("undo"):
        name, made = obj.name, out["objects"][1:]
        try:
            bpy.ops.ed.undo()
        except RuntimeError as exc:
            out["undo_refused"] = str(exc).strip()
        else:
            obj = bpy.data.objects[name]      # (undo reloads the data: references from before are gone)
            out["undone"] = compare(mesh_state(obj), before)
            out["undo_removed"] = all(bpy.data.objects.get(name) is None for name in made)
    if job.get("revert"):
        made = out["objects"][1:]
        bpy.ops.cgaskin.revert()
        out["reverted"] = compare(mesh_state(obj), before)
        out["made_removed"] = all(bpy.data.objects.get(name) is None for name in made)
    return out


def compare(state: dict, before: dict) -> dict:
    return {key: bool(np.array_equal(np.asarray(state[key]), np.asarray(before[key])))
            for key in ("co", "n_polygons", "weights", "uv", "materials")}


def main(jobs_path: str, out_path: str) -> None:
    results = []
    for job in json.loads(Path(jobs_path).read_text()):
        try:
            results.append(run_job(job))
        except Exception:
            results.append({"crash": traceback.format_exc()})
    Path(out_path).write_text(json.dumps(results))


if __name__ == "__main__":
    main(*sys.argv[1:3])
