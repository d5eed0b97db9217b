"""Progressive surgery: an incision made of many short strokes, each continuing the last.

    python -m benchmarks.bench_progressive [--strokes 200] [--large-strokes 20] [--large-faces 1500000]

Rows: Arm5.glb (the paper's arm; the procedural capsule when the model folder is absent) with
``--strokes`` strokes, and the procedural capsule subdivided to about ``--large-faces`` faces with
``--large-strokes`` strokes. The incision runs along the mesh's longest principal axis, over the longest
stretch between 10 % and 90 % of its length where the blades meet the surface, at an angle to the other
axes (so that it does not aim along rows of vertices); the blade at each step goes from outside the
surface to the centre of the mesh's slab there, and stroke i's blade at t_(i+1) is stroke
i+1's blade at t_i, so every stroke continues the slit.

Columns: the median milliseconds per stroke over the first and the last tenth of the strokes (a flat
cost shows that a stroke costs what it touches, a growing one that it costs the whole mesh), the median
over all, and the memory the strokes took at their peak (the process's peak resident memory from the
moment the model was built, less its resident memory then; Linux ``clear_refs``) against the bytes of
the mesh's own arrays (positions, faces, joints, weights, attributes), and the median minor page
faults per stroke (``resource.getrusage``: fresh pages the operating system mapped and zeroed for the
stroke, time that goes to memory rather than to the work). Two ways per model, each run in its own
process after a warm-up that compiles every kernel: the functional API (``cgaskin.tear`` on the rig
the previous stroke returned: a new rig per stroke, whose BVH is built again) and the editing session
(``cgaskin.Surgery(rig).tear``: arrays with spare capacity, a BVH updated in place).
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ._report import benchmark_parser, writes_tables
from ._timing import minor_faults, print_table


def _model(name: str, faces: int):
    import cgaskin
    from .bench_tear import models_dir
    if name == "arm5":
        path = models_dir() / "Arm5.glb"
        return (cgaskin.load(path), "Arm5.glb") if path.exists() else (cgaskin.capsule_arm(), "capsule_arm()")
    # capsule_arm has 2 * around * rings side faces (3 segments of rings_per_segment rings): choose
    # around : rings ≈ 1 : 3 for near-square faces on the 3-long, 0.25-radius arm
    around = max(16, int(round((faces / 6) ** 0.5 / 1.7)))
    rings = max(4, int(round(faces / (2 * around * 3))))
    rig = cgaskin.capsule_arm(rings_per_segment=rings, segments_around=around)
    return rig, f"capsule_arm({rings}, {around})"


def _blades(vertices, axes, along, steps, reach):
    """(len(steps), 2, 3) blades: handle outside, tip at the centre of the mesh's slab at each step
    (inside a bent limb, unlike the axis), at an irrational angle between the other two axes."""
    angle = 0.5 * (np.sqrt(5.0) - 1.0)
    radial = np.cos(angle) * axes[1] + np.sin(angle) * axes[2]
    half = 0.03 * (along.max() - along.min())
    centres = np.array([vertices[np.abs(along - s) <= half].mean(axis=0) for s in steps])
    # a smooth curve through the slab centres (a cubic in the step), exactly at each step along the axis,
    # so that consecutive blades differ by a short move and the skin they meet moves continuously
    fit = np.polynomial.polynomial.polyfit(steps, centres, min(3, len(steps) - 1))
    tips = np.polynomial.polynomial.polyval(steps, fit).T
    tips += (steps - tips @ axes[0])[:, None] * axes[0]
    return np.stack([tips + reach * radial, tips], axis=1)


def incision(rig, strokes: int):
    """(strokes + 1, 2, 3) blades along the longest principal axis, over the longest stretch between
    10 % and 90 % of the mesh's length where every blade meets the surface."""
    import cgaskin
    vertices = np.asarray(rig.vertices, np.float64)
    centre = vertices.mean(axis=0)
    _, _, axes = np.linalg.svd(vertices - centre, full_matrices=False)
    along = vertices @ axes[0]
    reach = 2.0 * float(np.linalg.norm(vertices - centre, axis=1).max())
    probe = np.linspace(*np.quantile(along, [0.1, 0.9]), 400)
    bvh = cgaskin.TriangleBVH(vertices, np.asarray(rig.faces))
    points = []
    for a, b in _blades(vertices, axes, along, probe, reach):
        face, t = bvh.first_hit(a, b)
        points.append(a + t * (b - a) if face >= 0 else np.full(3, np.nan))
    # a probe continues the run when its blade meets the skin close to where the previous one did (no
    # jump to another fold of the surface between them)
    gap = np.linalg.norm(np.diff(points, axis=0), axis=1)
    hits = [True] + list(gap <= 4.0 * (probe[1] - probe[0]))
    best, start = (0, 0), None
    for i, hit in enumerate(hits + [False]):
        if hit and start is None:
            start = i
        elif not hit and start is not None:
            best, start = max(best, (i - start, start)), None
    length, first = best
    steps = np.linspace(probe[first], probe[first + length - 1], strokes + 1)
    return _blades(vertices, axes, along, steps, reach)


def mesh_bytes(rig) -> int:
    arrays = [rig.vertices, rig.faces, rig.joints, rig.weights, *rig.attributes.values()]
    return int(sum(np.asarray(a).nbytes for a in arrays))


def _rss(field: str) -> int:
    """Bytes of /proc/self/status's ``field`` (VmRSS now, VmHWM the peak since the last reset)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _warm_up(api) -> None:
    """Compile every kernel a stroke runs (on the built-in capsule), so that no stroke times it."""
    import cgaskin
    rig = cgaskin.capsule_arm()
    blades = incision(rig, 3)
    session = cgaskin.Surgery(rig)
    for i in range(3):
        api(rig, session, blades[i], blades[i + 1])


def _functional(rig, _session, scalpel_from, scalpel_to):
    import cgaskin
    return cgaskin.tear(rig, scalpel_from, scalpel_to)


def _in_session(rig, session, scalpel_from, scalpel_to):
    session.tear(scalpel_from, scalpel_to)
    return rig


def run_one(name: str, strokes: int, faces: int, api_name: str) -> dict:
    """One model and one API, in this process: per-stroke seconds and the strokes' peak memory."""
    import cgaskin
    api = {"functional": _functional, "session": _in_session}[api_name]
    _warm_up(api)
    rig, label = _model(name, faces)
    blades = incision(rig, strokes)
    base = mesh_bytes(rig)
    Path("/proc/self/clear_refs").write_text("5")         # VmHWM := VmRSS from here on
    resident = _rss("VmRSS")
    session = cgaskin.Surgery(rig) if api_name == "session" else None
    seconds, faults = [], []
    for i in range(strokes):
        faults.append(-minor_faults())
        start = time.perf_counter()
        rig = api(rig, session, blades[i], blades[i + 1])
        seconds.append(time.perf_counter() - start)
        faults[-1] += minor_faults()
    n_faces = session.n_faces if session is not None else rig.n_faces
    return {"label": label, "faces": int(n_faces), "seconds": seconds, "faults": faults, "mesh_bytes": base,
            "peak": _rss("VmHWM") - resident}


@writes_tables
def main(argv=None) -> None:
    parser = benchmark_parser(__doc__)
    parser.add_argument("--strokes", type=int, default=200)
    parser.add_argument("--large-strokes", type=int, default=20)
    parser.add_argument("--large-faces", type=int, default=1_500_000)
    parser.add_argument("--one", nargs=4, metavar=("MODEL", "STROKES", "FACES", "API"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:                                   # the child process of one row
        print(json.dumps(run_one(args.one[0], int(args.one[1]), int(args.one[2]), args.one[3])))
        return
    rows = []
    for name, strokes in (("arm5", args.strokes), ("large", args.large_strokes)):
        medians = {}
        for api in ("functional", "session"):
            out = subprocess.run([sys.executable, "-m", "benchmarks.bench_progressive", "--one", name, str(strokes),
                                  str(args.large_faces), api], capture_output=True, text=True,
                                 cwd=Path(__file__).resolve().parent.parent)
            if out.returncode:
                print(out.stderr, file=sys.stderr)
                raise SystemExit(f"bench_progressive: the {name} {api} run failed")
            r = json.loads(out.stdout.strip().splitlines()[-1])
            ms = np.array(r["seconds"]) * 1e3
            tenth = max(1, len(ms) // 10)
            medians[api] = float(np.median(ms))
            rows.append([r["label"], api, r["faces"], len(ms), float(np.median(ms[:tenth])),
                         float(np.median(ms[-tenth:])), medians[api], medians["functional"] / medians[api],
                         float(np.median(r["faults"])),
                         r["peak"] / 2**20, r["mesh_bytes"] / 2**20, r["peak"] / r["mesh_bytes"]])
    print_table("progressive incision: each stroke continues the last",
                ["model", "API", "faces after", "strokes", "first 10% ms", "last 10% ms", "median ms",
                 "speed-up", "faults / stroke", "strokes' peak MiB", "mesh MiB", "peak / mesh"], rows)


if __name__ == "__main__":
    main()
