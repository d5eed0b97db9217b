"""The Blender extension: a cut of a 100k-face posed character, operator call to updated mesh, against
Blender's own bisect of the same mesh; and the routes for writing vertex-group weights. Run it with the
Python that has bpy (Blender 5.0 as a module, scripts/install-test-deps.sh):

    ~/.cache/cgaskin/bpy-5.0.1/bin/python -m benchmarks.bench_blender [--repeat 7] [--rings 30] [--around 200]

Rows (medians; ratios within this run):

* the capsule arm (``capsule_arm(n_joints=5, rings_per_segment=30, segments_around=200)``, 99.6k
  triangles, imported with Blender's glTF importer, posed at 0.4 s of its clip), ``bpy.ops.cgaskin.cut``
  warm: the whole call, the geometry (the call without the vertex-group transfers) and each stage
  (``cgaskin_blender.surgery.Times``); against ``bmesh.ops.bisect_plane`` of the same mesh at rest
  (Blender's bisect: a static mesh, no weights kept apart, no pose), mesh to BMesh and back included.
* writing the weights of the cut's larger half (Blender has no bulk write): ``VertexGroup.add`` once
  per group and distinct weight (the extension's route), once per vertex and group (as Blender's glTF
  importer does), and one float attribute per group converted by ``geometry.attribute_convert``.
"""
from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import bpy
import bmesh  # (importable once bpy is)

import cgaskin

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "blender"))
import cgaskin_blender  # noqa: E402
from cgaskin_blender import mesh_out, surgery  # noqa: E402


def quiet():
    """Keep what Blender prints (the importer's progress, the operators' reports) out of the tables."""
    return contextlib.redirect_stdout(io.StringIO())


def capsule_scene(rings: int, around: int, folder: Path):
    """The posed capsule arm in an empty scene, active, and an empty across its middle."""
    path = cgaskin.save(cgaskin.capsule_arm(n_joints=5, rings_per_segment=rings, segments_around=around),
                        folder / "capsule.glb")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with quiet():
        bpy.ops.import_scene.gltf(filepath=str(path))
    (obj,) = [o for o in bpy.context.scene.objects if o.type == "MESH" and o.find_armature() is not None]
    bpy.context.view_layer.objects.active = obj
    scene = bpy.context.scene
    scene.frame_set(int(0.4 * scene.render.fps))
    plane = bpy.data.objects.new("plane", None)
    plane.location = (1.45, 0.0, 0.0)
    plane.rotation_euler = (0.0, 1.3, 0.2)
    scene.collection.objects.link(plane)
    return obj, plane


def cut_rows(obj, plane, repeat: int) -> list:
    stages = []

    def cut():
        with quiet():
            bpy.ops.cgaskin.cut(plane=plane.name)
        stages.append(surgery.LAST[0].times)

    samples = []
    for k in range(repeat + 1):
        surgery.revert(obj)
        start = time.perf_counter()
        cut()
        if k:                                   # (the first call is the warm-up)
            samples.append(time.perf_counter() - start)
    times = stages[1:]
    total = float(np.median(samples))
    median = {field: float(np.median([getattr(t, field) for t in times])) for field in times[0]._fields}
    geometry = float(np.median([s - t.weights_in - t.weights_out for s, t in zip(samples, times)]))

    def bisect():
        mesh = obj.data
        work = bmesh.new()
        work.from_mesh(mesh)
        bmesh.ops.bisect_plane(work, geom=work.verts[:] + work.edges[:] + work.faces[:], dist=1e-6,
                               plane_co=tuple(plane.location), plane_no=tuple(plane.matrix_world.col[2][:3]),
                               clear_outer=False, clear_inner=False)
        out = bpy.data.meshes.new("bisected")
        work.to_mesh(out)
        work.free()
        bpy.data.meshes.remove(out)

    surgery.revert(obj)
    bisect_s = median_seconds(bisect, repeat)
    faces = len(obj.data.polygons)
    rows = [["cgaskin.cut operator, whole call", faces, total * 1e3, total / bisect_s],
            ["  geometry (call less the weight transfers)", faces, geometry * 1e3, geometry / bisect_s]]
    rows += [[f"    {name.replace('_', ' ')}", faces, value * 1e3, value / bisect_s] for name, value in median.items()]
    rows.append(["Blender's bisect_plane (BMesh, at rest)", faces, bisect_s * 1e3, 1.0])
    return rows


def weight_rows(obj, repeat: int) -> list:
    """Writing the weights of the cut's first object again, by three routes."""
    with quiet():
        bpy.ops.cgaskin.cut(plane="plane")
    outcome = surgery.LAST[0]
    weights = mesh_out.result_weights(outcome.results[0], outcome.welds[0], outcome.source)
    names = [group.name for group in obj.vertex_groups]
    bare = obj.data.copy()

    def fresh():
        target = bpy.data.objects.new("weights", bare.copy())
        bpy.context.scene.collection.objects.link(target)
        for name in names:
            target.vertex_groups.new(name=name)
        return target

    def timed(route) -> float:
        samples = []
        for _ in range(repeat):
            target = fresh()
            start = time.perf_counter()
            route(target)
            samples.append(time.perf_counter() - start)
            mesh = target.data
            bpy.data.objects.remove(target)
            bpy.data.meshes.remove(mesh)
        return float(np.median(samples))

    def per_vertex(target):
        groups = target.vertex_groups
        for v, g, w in zip(weights.vertex.tolist(), weights.group.tolist(), weights.weight.tolist()):
            groups[g].add([v], w, "REPLACE")

    def converted(target):
        n = len(target.data.vertices)
        for g, name in enumerate(names):
            pick = weights.group == g
            dense = np.zeros(n, dtype=np.float32)
            dense[weights.vertex[pick]] = weights.weight[pick]
            attribute = target.data.attributes.new("w", "FLOAT", "POINT")
            attribute.data.foreach_set("value", dense)
            target.data.attributes.active = attribute
            target.vertex_groups.remove(target.vertex_groups[name])
            with bpy.context.temp_override(object=target, active_object=target):
                bpy.ops.geometry.attribute_convert(mode="VERTEX_GROUP")
            target.vertex_groups[-1].name = name

    routes = {"VertexGroup.add per group and weight (the extension)": lambda t: mesh_out.write_weights(t, weights),
              "VertexGroup.add per vertex and group (glTF importer)": per_vertex,
              "attribute_convert per group": converted}
    seconds = {name: timed(route) for name, route in routes.items()}
    slowest = seconds["VertexGroup.add per vertex and group (glTF importer)"]
    return [[name, len(weights.vertex), value * 1e3, value / slowest] for name, value in seconds.items()]


@writes_tables
def main(argv=None):
    parser = benchmark_parser(__doc__)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--rings", type=int, default=30, help="capsule rings per bone segment (5 bones)")
    parser.add_argument("--around", type=int, default=200, help="capsule vertices per ring")
    args = parser.parse_args(argv)
    cgaskin_blender.register()
    with tempfile.TemporaryDirectory() as folder:
        obj, plane = capsule_scene(args.rings, args.around, Path(folder))
        print_table("a cut of the posed capsule arm in Blender, warm (ms, median)",
                    ["operation", "faces", "ms", "x bisect"], cut_rows(obj, plane, args.repeat))
        surgery.revert(obj)
        print_table("writing the larger half's vertex-group weights (ms, median)",
                    ["route", "weights", "ms", "x per vertex"], weight_rows(obj, args.repeat))


if __name__ == "__main__":
    main()
