"""Drilling: cgaskin.drill against a cut of the same model, and against manifold3d's mesh boolean, in one
process.

    python -m benchmarks.bench_drill [--repeat 7] [--large-rings 410] [--large-around 512]

Rows (medians; ratios within this run):

* Arm5.glb (5037 faces): a hole through the forearm, walled and open, and in a pose (the forearm bent),
  against ``cgaskin.cut`` of the same rig through the same point (the issue's bar: a drill at most 8x a
  cut); each sample times calls in a loop of at least 20 ms;
* the capsule arm of the playing-model issue (``capsule_arm(rings_per_segment=410, segments_around=512)``,
  about 1.5M faces): a hole in a ``Surgery`` then its undo, at rest and in a new pose each hole (the
  bar: 20 ms, growing with the faces near the bit, not with the mesh: the same holes in a capsule a
  third as long, as finely meshed), the functional ``drill`` of the rig, and manifold3d's difference of
  the welded mesh and a 64-sided bit (the mesh converted to a Manifold and back, as a user of it would),
  when manifold3d is installed (``pip install manifold3d``).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

import cgaskin

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table
from .bench_tear import models_dir

FOREARM = "Character1_RightForeArm"


def arm_rows(repeat: int) -> list:
    """Arm5: a hole through the forearm, walled, open and posed, against a cut through the same point."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rig = cgaskin.load(models_dir() / "Arm5.glb")
    start, end, radius = np.array([-1.0, 36.0, -12.0]), np.array([-1.0, 36.0, 12.0]), 1.5
    pose = rig.rest_pose().rotate(FOREARM, [1, 0, 0], np.radians(10))
    calls = {"cut through the same point": lambda: cgaskin.cut(rig, [0, 1, 0], start),
             "drill, walled": lambda: cgaskin.drill(rig, start, end, radius),
             "drill, open (wall=False)": lambda: cgaskin.drill(rig, start, end, radius, wall=False),
             "drill, walled, in a pose": lambda: cgaskin.drill(rig, start, end, radius, pose=pose)}
    # (a call of a millisecond or less timed alone is mostly noise on a shared machine)
    ms = {name: median_seconds(fn, repeat, min_time=0.02) * 1e3 for name, fn in calls.items()}
    cut_ms = ms["cut through the same point"]
    return [["Arm5.glb", rig.n_faces, name, value, value / cut_ms] for name, value in ms.items()]


def _manifold_difference(vertices, faces, start, end, radius):
    """manifold3d's difference of the (welded, closed) mesh and the bit, converted there and back."""
    import manifold3d
    mesh = manifold3d.Manifold(manifold3d.Mesh(vert_properties=vertices.astype(np.float32),
                                               tri_verts=faces.astype(np.uint32)))
    length = float(np.linalg.norm(end - start))
    bit = manifold3d.Manifold.cylinder(length, radius, radius, 64) + manifold3d.Manifold.sphere(radius, 64) \
        + manifold3d.Manifold.sphere(radius, 64).translate([0.0, 0.0, length])
    bit = bit.translate(list(start))                  # (the travel is along +z here)
    return (mesh - bit).to_mesh()


def _session_hole_ms(rig, places, travel, radius, repeat: int) -> float:
    """Median ms of a walled hole in a ``Surgery`` of ``rig`` then its undo, at each of ``places``."""
    session = cgaskin.Surgery(rig)

    def holes():
        for p in places:
            session.drill(p, p + travel, radius)
            session.undo()
    return median_seconds(holes, max(1, repeat // 3), warmup=1) * 1e3 / len(places)


def _posed_session_hole_ms(rig, places, travel, radius, repeat: int) -> float:
    """Median ms of a walled hole in a ``Surgery`` of ``rig`` then its undo, at each of ``places``, each
    hole in a pose the session has not drilled in before (the elbow turned a little more each time)."""
    session = cgaskin.Surgery(rig)
    turns = iter(range(1, 1_000_000))

    def holes():
        for p in places:
            pose = rig.rest_pose().rotate("elbow", [0, 0, 1], np.radians(0.01 * next(turns)))
            session.drill(p, p + travel, radius, pose=pose)
            session.undo()
    return median_seconds(holes, max(1, repeat // 3), warmup=1) * 1e3 / len(places)


def large_rows(rings: int, around: int, repeat: int) -> list:
    """The large capsule: holes across it at several places, in a session (undone after each), the same
    holes in a capsule a third as long (the same faces near the bit, a third of the mesh), as a
    functional drill, and manifold3d's boolean when it installs."""
    from cgaskin.surgery.topology import topology
    rig = cgaskin.capsule_arm(rings_per_segment=rings, segments_around=around)
    places = [np.array([x, 0.0, -1.0]) for x in (0.6, 1.4, 2.2)]
    radius, travel = 0.05, np.array([0.0, 0.0, 2.0])
    rows = []
    start = time.perf_counter()
    cgaskin.Surgery(rig)
    rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "Surgery(rig) (once)",
                 (time.perf_counter() - start) * 1e3, ""])
    session_ms = _session_hole_ms(rig, places, travel, radius, repeat)
    rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "Surgery.drill, a walled hole, then undo", session_ms,
                 1.0])
    posed_ms = _posed_session_hole_ms(rig, places, travel, radius, repeat)
    rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "the same, each hole in a new pose", posed_ms,
                 posed_ms / session_ms])
    short = cgaskin.capsule_arm(n_joints=1, length=1.0, rings_per_segment=rings, segments_around=around)
    short_ms = _session_hole_ms(short, [p * [1.0 / 3.0, 1.0, 1.0] for p in places], travel, radius, repeat)
    rows.append([f"capsule_arm(1 joint, length 1, {rings}, {around})", short.n_faces,
                 "the same holes, a third of the mesh", short_ms, short_ms / session_ms])
    functional_ms = median_seconds(lambda: cgaskin.drill(rig, places[0], places[0] + travel, radius),
                                   max(1, repeat // 3), warmup=1) * 1e3
    rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "cgaskin.drill (functional)", functional_ms,
                 functional_ms / session_ms])
    try:
        import manifold3d  # noqa: F401
    except ImportError:
        rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "manifold3d: not installed", "", ""])
        return rows
    t = topology(rig.vertices, rig.faces)
    welded = np.asarray(rig.vertices)[t.representative]
    boolean_ms = median_seconds(lambda: _manifold_difference(welded, t.faces, places[0], places[0] + travel, radius),
                                max(1, repeat // 3), warmup=0) * 1e3
    rows.append([f"capsule_arm({rings}, {around})", rig.n_faces, "manifold3d difference (64-sided bit)", boolean_ms,
                 boolean_ms / session_ms])
    return rows


@writes_tables
def main(argv=None):
    parser = benchmark_parser(__doc__)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--large-rings", type=int, default=410, help="capsule rings per segment (0: skip)")
    parser.add_argument("--large-around", type=int, default=512)
    args = parser.parse_args(argv)
    print_table("Arm5: a hole through the forearm (ms, median)", ["model", "faces", "operation", "ms", "x cut"],
                arm_rows(args.repeat))
    if args.large_rings:
        print_table("the large capsule: one hole (ms, median)", ["model", "faces", "operation", "ms", "x session"],
                    large_rows(args.large_rings, args.large_around, args.repeat))


if __name__ == "__main__":
    main()
