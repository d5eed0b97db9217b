"""One animation frame of a real model: hierarchy evaluation (versor products along the skeleton,
inverse bind matrices, hoisted affines) plus the blend loop, against the paper's approach and
matrix baselines, in one process.

    python -m benchmarks.bench_frame [--model PATH] [--paper-frames 1]

Rows (median of repeated frames): cgaskin.skin(rig, pose) (all of it: bone affines + blend), the
bone-affine half alone, matrix LBS in numpy with the same bone matrices, Kavan DQS in numpy, and
the paper's per-vertex clifford sandwich loop (timed on a few frames only: it takes ~0.5 s each).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin import baselines

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table

DEFAULT_MODEL = Path(os.environ.get("CGASKIN_MODELS", Path(__file__).resolve().parents[2] / "shared" / "models")) / "Arm5.glb"


def paper_frame(rig, pose):
    """The paper's approach: per vertex, per influence, a clifford sandwich on a conformal point."""
    from clifford.g3c import down, up
    from cgaskin import versor
    bones = pose.bone_affines().reshape(-1, 3, 4)
    # the bone transforms as clifford versors (the paper holds M_nk B_n as multivectors)
    mats = np.zeros((len(bones), 4, 4))
    mats[:, :3] = bones
    mats[:, 3, 3] = 1
    mvs = [versor.to_clifford(versor.from_matrix(m, tolerance=1e-3)) for m in mats]
    out = np.empty_like(rig.vertices)
    for i, (x, js, ws) in enumerate(zip(rig.vertices, rig.joints, rig.weights)):
        X = up(x[0] * cgaskin_e[0] + x[1] * cgaskin_e[1] + x[2] * cgaskin_e[2])
        acc = 0
        for j, w in zip(js, ws):
            if w:
                acc = acc + w * (mvs[j] * X * ~mvs[j])
        out[i] = down(acc).value[1:4]
    return out


cgaskin_e = None


@writes_tables
def main(argv=None):
    global cgaskin_e
    ap = benchmark_parser(__doc__)
    ap.add_argument("--model", default=str(DEFAULT_MODEL))
    ap.add_argument("--paper-frames", type=int, default=1, help="frames of the paper's clifford loop (0: skip)")
    args = ap.parse_args(argv)
    rig = cgaskin.load(args.model)
    sk = rig.skeleton
    # a frame: bend a joint in the middle of the chain and dilate another
    pose = rig.rest_pose().rotate(sk.bone_nodes[sk.n_bones // 2], [0, 0, 1], 0.4).dilate(sk.bone_nodes[-1], 1.3)
    out = np.empty_like(rig.vertices)
    mats = np.zeros((sk.n_bones, 4, 4))
    mats[:, :3] = pose.bone_affines().reshape(-1, 3, 4)
    mats[:, 3, 3] = 1
    rows = []
    t_frame = median_seconds(lambda: cgaskin.skin(rig, pose, out=out), 51, min_time=0.02)
    rows.append(["cgaskin.skin (hierarchy + affines + blend)", t_frame * 1e6, 1.0])
    t_aff = median_seconds(pose.bone_affines, 51, min_time=0.02)
    rows.append(["  of which Pose.bone_affines (hierarchy)", t_aff * 1e6, t_frame / t_aff])
    t_lbs = median_seconds(lambda: baselines.lbs_matrices(rig.vertices, rig.joints, rig.weights, mats), 21, min_time=0.02)
    rows.append(["numpy matrix LBS (blend only)", t_lbs * 1e6, t_frame / t_lbs])
    t_dqs = median_seconds(lambda: baselines.dqs(rig.vertices, rig.joints, rig.weights, mats), 11, min_time=0.02)
    rows.append(["numpy DQS (blend only)", t_dqs * 1e6, t_frame / t_dqs])
    if args.paper_frames:
        from clifford import g3c
        cgaskin_e = (g3c.e1, g3c.e2, g3c.e3)
        paper_frame(rig, pose)                         # warm clifford's JIT
        t_paper = median_seconds(lambda: paper_frame(rig, pose), args.paper_frames, warmup=0)
        err = np.abs(paper_frame(rig, pose) - cgaskin.skin(rig, pose)).max()
        rows.append([f"paper: per-vertex clifford sandwich (max diff {err:.1e})", t_paper * 1e6, t_frame / t_paper])
    print_table(f"One frame of {Path(args.model).name}: {rig.n_vertices} vertices, {sk.n_bones} bones, "
                f"{sk.n_nodes} nodes (median µs)", ["method", "µs", "x cgaskin"], rows)


if __name__ == "__main__":
    main()
