"""Plane-cut timings: cgaskin.cut against trimesh and the paper's figures, in one process.

    python -m benchmarks.bench_cut [--repeat 21] [--big-faces 1000000] [--models DIR]

Rows (medians; ratios within this run):

* the arm (Arm5.glb, 5037 faces) and the cylinders (3Cylinder4bones.glb, 758 faces), cut through the
  centre of the bounding box across the longest axis: ``cgaskin.cut`` (both output rigs, weights,
  attributes; the welded topology is cached per rig, its one-off build is a row of its own), posed,
  and capped; ``trimesh.Trimesh(vertices, faces, process=False).slice_plane(point, normal, cap=False)``
  on the same mesh, as it is: it returns ONE side and carries no weights, so it does less work;
* a capsule of about 1M faces (``capsule_arm`` finely subdivided, smooth 2-bone weights), same rows;
* the paper's figures (pure Python + clifford, on its own machine): arm cut 22805 ms, cylinders 898 ms.

Each cut is timed first on its own (the rig just built and cut once), then each after a skin of the
same rig in a pose (what the allocator holds then differs). ``page faults``: the median minor page
faults per call (``resource.getrusage``): fresh pages the operating system mapped and zeroed for the
call, time spent on memory rather than on the cut.

Targets: arm cut <= 0.5 ms, 1M-face cut <= 15 ms in either order.
"""
from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin import capsule_arm, cut
from cgaskin.surgery.topology import topology

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table, timed

PAPER_MS = {"arm": 22805.0, "cylinders": 898.0}
TARGET_MS = {"arm": 0.5, "1M faces": 15.0}


def _plane(vertices):
    """Through the bounding-box centre, normal along the longest extent tilted a little (a generic
    plane: not parallel to any face of an axis-aligned model)."""
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    normal = np.eye(3)[int(np.argmax(hi - lo))] + np.array([0.05, 0.1, 0.07])
    return normal / np.linalg.norm(normal), 0.5 * (lo + hi)


def _big_rig(faces: int):
    """A capsule arm with about ``faces`` faces (rings of 512 vertices)."""
    segments = 512
    rings = max(1, round(faces / (2 * segments * 3)))
    return capsule_arm(rings_per_segment=rings, segments_around=segments)


def _trimesh_slice(rig, normal, point):
    try:
        import trimesh
    except ImportError:
        return None
    mesh = trimesh.Trimesh(rig.vertices, rig.faces, process=False)
    return lambda: mesh.slice_plane(point, normal, cap=False)


def _rows(label, rig, repeat, min_time):
    normal, point = _plane(rig.vertices)
    pose = rig.pose(0, 0.7 * rig.clips[0].duration) if rig.clips else _bent_pose(rig)
    posed_point = cgaskin.skin(rig, pose).mean(axis=0)
    cut(rig, normal, point)                                  # builds and caches the topology
    # the cut first (nothing else freed memory since the rig was built), then each cut after a skin
    # of the same rig (its (n, 3) array freed: the allocator state a session or a viewer leaves)
    t_cut = timed(lambda: cut(rig, normal, point), repeat, min_time=min_time)
    t_after_skin = timed(lambda: cut(rig, normal, point), repeat, before=lambda: cgaskin.skin(rig, pose))
    t_posed = timed(lambda: cut(rig, normal, posed_point, pose=pose), repeat, min_time=min_time)
    t_cap = timed(lambda: cut(rig, normal, point, cap=True), repeat, min_time=min_time)
    t_topology = timed(lambda: topology(rig.vertices, rig.faces), repeat, min_time=min_time)
    slice_fn = _trimesh_slice(rig, normal, point)
    t_trimesh = median_seconds(slice_fn, repeat, min_time=min_time) if slice_fn else float("nan")
    paper = PAPER_MS.get(label)
    target = TARGET_MS.get(label)
    faces = len(rig.faces)

    def row(what, timing, ref=None, ref_name=""):
        t, faults = timing
        met = "" if target is None or what not in ("cut", "cut, after a skin") else \
            f"<= {target:g} ms {'ok' if t * 1e3 <= target else 'MISSED'}"
        return [f"{label}: {what}", faces, t * 1e3, faults,
                f"{ref_name} {ref:.4g} ms (x{ref / (t * 1e3):.3g})" if ref is not None else "", met]

    rows = [row("cut", t_cut, t_trimesh * 1e3, "trimesh slice_plane"),
            row("cut, after a skin", t_after_skin, t_trimesh * 1e3, "trimesh slice_plane"),
            row("posed cut", t_posed), row("cut, cap=True", t_cap),
            row("welded topology (once per rig)", t_topology)]
    if paper:
        rows.insert(1, row("cut vs paper", t_cut, paper, "paper"))
    return rows


def _bent_pose(rig):
    """A pose bending every node a little about a fixed axis (for models without clips)."""
    pose = rig.rest_pose()
    for node in range(1, rig.skeleton.n_nodes):
        pose = pose.rotate(node, [0.3, 0.2, 0.93], 0.2)
    return pose


@writes_tables
def main(argv=None):
    ap = benchmark_parser(__doc__)
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--big-faces", type=int, default=1_000_000)
    ap.add_argument("--models", default=os.environ.get("CGASKIN_MODELS",
                                                       Path(__file__).resolve().parents[1].parent / "shared" / "models"))
    args = ap.parse_args(argv)
    models = Path(args.models)

    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                     # assimp files' weight sums (rigs/gltf.py)
        named = [("arm", "Arm5.glb"), ("cylinders", "3Cylinder4bones.glb")]
        for label, name in named:
            if (models / name).is_file():
                rows += _rows(label, cgaskin.load(models / name), args.repeat, 0.05)
            else:
                print(f"(skipping {label}: {models / name} not found; set --models or CGASKIN_MODELS)")
    rows += _rows("capsule", capsule_arm(), args.repeat, 0.05)
    big = _big_rig(args.big_faces)
    rows += _rows("1M faces" if abs(len(big.faces) - 1e6) < 3e5 else f"{len(big.faces)} faces",
                  big, max(3, args.repeat // 4), 0.0)
    print_table(f"Plane cut (median of {args.repeat}; cgaskin returns both rigs with weights and "
                f"attributes, trimesh slice_plane one side, geometry only; paper: its machine)",
                ["case", "faces", "cgaskin ms", "page faults", "reference", "target"], rows)


if __name__ == "__main__":
    main()
