"""Render the guide's Blender picture: the Fox torn along its flank and drilled through, in Cycles.

A documentation step run by hand (not in CI, not by ``scripts/build-docs.sh``): from the repository
root, in the Python that has Blender as a module (``bpy`` 5.0, the tests' venv),

    ~/.cache/cgaskin/bpy-5.0.1/bin/python docs/blender/render_picture.py [MODELS] [--out PNG]
                                                                         [--samples N] [--scale PERCENT]

MODELS is the folder with Fox.glb (default: ``$CGASKIN_MODELS``, else ``../shared/models`` next to the
repository); the picture goes to ``docs/screenshots/blender_fox_torn_drilled.png``. It loads the
extension from ``blender/`` (no installed extension needed), imports Fox.glb with Blender's glTF
importer, poses it at a frame of its "Survey" clip, draws a stroke on the posed flank (a curve through
points found by ray casts), runs ``cgaskin.tear`` with an opening and ``cgaskin.drill`` with a wall
along an empty's Z axis, then renders one frame on the CPU with Cycles (900 x 600, 32 samples,
OpenImageDenoise) and prints how long each step took. The inside of the body (seen through the slit)
and the drilled hole's wall are shaded a flesh colour, so both read at a glance.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "blender"))
import cgaskin_blender  # noqa: E402

#: the posed frame (in Survey the fox stands and looks around: here its head is lowered)
CLIP, FRAME = "Survey", 30
#: where on the posed body the stroke and the hole go, as fractions of the posed box (x, y, z)
STROKE_HEIGHT, STROKE_FROM, STROKE_TO = 0.67, 0.20, 0.40
HOLE_AT = (0.47, 0.52)                  # (y, z)
#: the camera's view direction: from +X (the fox's right), a little from the front (-Y), from above
VIEW = (-1.0, 0.4, -0.42)
#: the drill's direction: into the right flank, turned halfway to the view so the hole shows through
HOLE_AXIS = (-1.0, 0.2, -0.15)
#: sizes relative to the posed box's diagonal
OPENING, HOLE_RADIUS = 0.03, 0.035
#: the flesh colour of the cut surfaces (linear RGB)
FLESH = (0.55, 0.06, 0.05, 1.0)
#: the face attribute that marks the drilled hole's wall (the material reads it)
WALL = "cgaskin_picture_wall"


def arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    default_models = os.environ.get("CGASKIN_MODELS", str(REPO.parent / "shared" / "models"))
    parser.add_argument("models", nargs="?", default=default_models, help="folder with Fox.glb")
    parser.add_argument("--out", default=str(REPO / "docs" / "screenshots" / "blender_fox_torn_drilled.png"))
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--scale", type=int, default=100, help="resolution percentage (drafts: 50)")
    return parser.parse_args()


def load_fox(models: Path):
    """The Fox's skinned mesh object, posed at ``FRAME`` of ``CLIP``, alone in an empty scene."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(models / "Fox.glb"))
    for other in [o for o in bpy.context.scene.objects if o.type == "MESH" and o.find_armature() is None]:
        bpy.data.objects.remove(other)       # (the file's stray icosphere)
    fox = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    fox.find_armature().animation_data.action = bpy.data.actions[CLIP]
    bpy.context.view_layer.objects.active = fox
    bpy.context.scene.frame_set(FRAME)
    return fox


def posed_positions(obj) -> np.ndarray:
    """(n, 3) world positions of ``obj``'s vertices as Blender's Armature modifier poses them."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    world = np.array(obj.matrix_world)
    return co.reshape(-1, 3).astype(np.float64) @ world[:3, :3].T + world[:3, 3]


def box_point(box: np.ndarray, fractions) -> Vector:
    """The point at ``fractions`` (x, y, z) of the (2, 3) box ``box``."""
    return Vector(box[0] + np.asarray(fractions) * (box[1] - box[0]))


def flank_stroke(box: np.ndarray):
    """A curve on the posed +X flank: points where rays along -X hit the mesh, along the body."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    points = []
    for y in np.linspace(STROKE_FROM, STROKE_TO, 9):
        origin = box_point(box, (1.5, y, STROKE_HEIGHT))
        hit, location, *_ = bpy.context.scene.ray_cast(depsgraph, origin, Vector((-1.0, 0.0, 0.0)))
        if hit:
            points.append(tuple(location))
    curve = bpy.data.curves.new("stroke", "CURVE")
    spline = curve.splines.new("POLY")
    spline.points.add(len(points) - 1)
    spline.points.foreach_set("co", np.c_[points, np.ones(len(points))].astype(np.float32).ravel())
    stroke = bpy.data.objects.new("stroke", curve)
    bpy.context.scene.collection.objects.link(stroke)
    return stroke


def drill_bit(box: np.ndarray):
    """An empty beside the +X flank whose Z axis (``HOLE_AXIS``) points through the body at
    ``HOLE_AT``."""
    axis = Vector(HOLE_AXIS).normalized()
    bit = bpy.data.objects.new("bit", None)
    bit.location = box_point(box, (0.5, *HOLE_AT)) - axis * float(np.linalg.norm(box[1] - box[0]))
    bit.rotation_euler = axis.to_track_quat("Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(bit)
    return bit


def mark_wall(obj, bit, radius: float) -> int:
    """Mark the faces of the drilled hole's wall in the face attribute ``WALL``: posed faces about
    ``radius`` from the bit's axis whose normals are across it. Returns how many."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    centers = np.empty(len(mesh.polygons) * 3, dtype=np.float32)
    normals = np.empty_like(centers)
    mesh.polygons.foreach_get("center", centers)
    mesh.polygons.foreach_get("normal", normals)
    evaluated.to_mesh_clear()
    world = np.array(obj.matrix_world)
    centers = centers.reshape(-1, 3) @ world[:3, :3].T + world[:3, 3]
    normals = normals.reshape(-1, 3) @ world[:3, :3].T
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    axis = np.array(bit.matrix_world)[:3, 2]
    axis /= np.linalg.norm(axis)
    offset = centers - np.array(bit.location)
    distance = np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1)
    wall = (np.abs(distance / radius - 1.0) < 0.15) & (np.abs(normals @ axis) < 0.5)
    attribute = obj.data.attributes.new(WALL, "FLOAT", "FACE")
    attribute.data.foreach_set("value", wall.astype(np.float32))
    return int(wall.sum())


def flesh_inside(material) -> None:
    """Shade the inside of the body (back faces, seen through the slit) and the hole's wall flesh-red
    in the imported material: its texture colour mixed with ``FLESH`` by max(backfacing, wall)."""
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    texture = bsdf.inputs["Base Color"].links[0].from_socket
    geometry = nodes.new("ShaderNodeNewGeometry")
    wall = nodes.new("ShaderNodeAttribute")
    wall.attribute_name = WALL
    either = nodes.new("ShaderNodeMath")
    either.operation = "MAXIMUM"
    links.new(geometry.outputs["Backfacing"], either.inputs[0])
    links.new(wall.outputs["Fac"], either.inputs[1])
    mix = nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    links.new(either.outputs["Value"], mix.inputs["Factor"])
    links.new(texture, mix.inputs["A"])
    mix.inputs["B"].default_value = FLESH
    links.new(mix.outputs["Result"], bsdf.inputs["Base Color"])
    # (the slit's inside gets no direct light: a faint glow keeps its colour from going black)
    glow = nodes.new("ShaderNodeMath")
    glow.operation = "MULTIPLY"
    links.new(either.outputs["Value"], glow.inputs[0])
    glow.inputs[1].default_value = 0.25
    bsdf.inputs["Emission Color"].default_value = FLESH
    links.new(glow.outputs["Value"], bsdf.inputs["Emission Strength"])


def stage(box: np.ndarray) -> None:
    """A camera framing the fox from its front right, a sun, a plain ground and a light background."""
    scene = bpy.context.scene
    low, high = box
    center = Vector((low + high) / 2)
    size = float(np.linalg.norm(high - low))
    ground = bpy.data.meshes.new("ground")
    ground.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
    ground_object = bpy.data.objects.new("ground", ground)
    ground_object.scale = (size * 20,) * 3
    ground_object.location = (center.x, center.y, low[2])
    grey = bpy.data.materials.new("ground")
    grey.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.55, 0.55, 0.55, 1.0)
    grey.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.9
    ground.materials.append(grey)
    scene.collection.objects.link(ground_object)

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.lens = 50
    view = Vector(VIEW).normalized()
    camera.location = center - view * size * 1.35
    camera.rotation_euler = view.to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera

    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.5
    sun.data.angle = np.radians(8)
    sun.rotation_euler = Vector((-0.6, 0.3, -1.0)).normalized().to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(sun)

    world = bpy.data.worlds.new("world")
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.8, 0.82, 0.85, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.world = world


def render_settings(out: Path, samples: int, scale: int) -> None:
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = True
    scene.cycles.use_denoising = True
    scene.cycles.denoiser = "OPENIMAGEDENOISE"
    scene.cycles.adaptive_threshold = 0.03
    scene.cycles.max_bounces = 3        # (an opaque fox on a matte ground: more bounces change little)
    scene.render.resolution_x, scene.render.resolution_y = 900, 600
    scene.render.resolution_percentage = scale
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    scene.render.filepath = str(out)


def main() -> None:
    args = arguments()
    cgaskin_blender.register()
    clock = time.perf_counter()
    fox = load_fox(Path(args.models))
    posed = posed_positions(fox)
    box = np.array([posed.min(axis=0), posed.max(axis=0)])
    size = float(np.linalg.norm(box[1] - box[0]))
    stroke = flank_stroke(box)
    bpy.ops.cgaskin.tear(stroke=stroke.name, blade_direction=(-1.0, 0.0, 0.0), opening=OPENING * size)
    tore = time.perf_counter()
    bit = drill_bit(box)
    bpy.ops.cgaskin.drill(bit=bit.name, radius=HOLE_RADIUS * size, wall=True)
    drilled = time.perf_counter()
    walls = mark_wall(fox, bit, HOLE_RADIUS * size)
    for helper in (stroke, bit):
        helper.hide_render = True
    flesh_inside(fox.data.materials[0])
    stage(box)
    render_settings(Path(args.out), args.samples, args.scale)
    start, start_cpu = time.perf_counter(), time.process_time()
    bpy.ops.render.render(write_still=True)
    done, done_cpu = time.perf_counter(), time.process_time()
    print(f"render_picture: tear (with the import) {tore - clock:.2f} s, drill {drilled - tore:.2f} s, "
          f"{walls} wall faces, render {done - start:.1f} s "
          f"(CPU {done_cpu - start_cpu:.1f} s; {args.samples} samples, {args.scale}%): "
          f"{args.out} ({Path(args.out).stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
