"""The paper's Fig. 1 on the shared models: one joint rotated, dilated or translated, skinned by the
CGA path and by independent matrix LBS and dual-quaternion skinning (Kavan), reporting the ℓ∞
difference relative to the bounding-box diagonal.

    python -m benchmarks.fig1_compare [--models DIR]

The matrix path builds every global transform with numpy matrices (baselines.global_matrices) from
the same TRS edits, so it shares nothing with the versor path but the file data.
"""
from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin import baselines

from ._report import benchmark_parser, writes_tables
from ._timing import print_table

MODELS = ["Arm5.glb", "3Cylinder4bones.glb", "PlaneWith3Bones.glb", "Fox.glb", "simple_skin.gltf"]
DEFAULT_DIR = Path(os.environ.get("CGASKIN_MODELS", Path(__file__).resolve().parents[2] / "shared" / "models"))


def _matrix(edit, pivot, amount):
    m = np.eye(4)
    if edit == "rotate":
        r = baselines.quat_to_matrix([0, 0, np.sin(amount / 2), np.cos(amount / 2)])
        m[:3, :3] = r
        m[:3, 3] = pivot - r @ pivot
    elif edit == "translate":
        m[:3, 3] = amount
    return m


def compare(rig, edit):
    sk = rig.skeleton
    counts = np.bincount(rig.joints[rig.weights > 0], minlength=sk.n_bones)
    bone = int(np.argsort(-counts)[min(1, sk.n_bones - 1)])      # a well-weighted joint
    node = int(sk.bone_nodes[bone])
    diag = float(np.linalg.norm(np.ptp(rig.vertices, axis=0)))
    rest = rig.rest_pose()
    local = rest.matrices.copy()
    pivot = local[node][:3, 3].copy()
    if edit == "rotate":
        pose = rest.rotate(node, [0, 0, 1], np.radians(60))
        local[node] = _matrix("rotate", pivot, np.radians(60)) @ local[node]
    elif edit == "dilate":
        pose = rest.dilate(node, 1.5)
        local[node] = local[node] @ np.diag([1.5, 1.5, 1.5, 1.0])
    else:
        v = np.array([0.05 * diag, 0, 0])
        pose = rest.translate(node, v)
        local[node] = _matrix("translate", pivot, v) @ local[node]
    bones = baselines.global_matrices(sk.parents, local)[sk.bone_nodes] @ sk.inverse_bind
    cga = cgaskin.skin(rig, pose)
    lbs = baselines.lbs_matrices(rig.vertices, rig.joints, rig.weights, bones)
    dqs = baselines.dqs(rig.vertices, rig.joints, rig.weights, bones)
    moved = np.abs(cga - cgaskin.skin(rig, rest)).max() / diag
    return sk.names[node], moved, np.abs(cga - lbs).max() / diag, np.abs(cga - dqs).max() / diag


@writes_tables
def main(argv=None):
    ap = benchmark_parser(__doc__)
    ap.add_argument("--models", default=str(DEFAULT_DIR))
    args = ap.parse_args(argv)
    rows = []
    for name in MODELS:
        path = Path(args.models) / name
        if not path.exists():
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rig = cgaskin.load(path)
        for edit in ("rotate", "dilate", "translate"):
            joint, moved, d_lbs, d_dqs = compare(rig, edit)
            rows.append([name, edit, joint, f"{moved:.3g}", f"{d_lbs:.1e}", f"{d_dqs:.1e}"])
    print_table("Fig. 1: CGA vs matrix LBS vs DQS, ℓ∞ difference / bounding-box diagonal "
                "(rotate 60° about z, dilate x1.5, translate 5% of the diagonal, at one joint)",
                ["model", "edit", "joint", "max move", "|CGA-LBS|", "|CGA-DQS|"], rows)
    print("\nCGA and matrix LBS blend the same affine maps (the versor sandwich hoisted to 3x4), so they "
          "agree to rounding (1e-16).\nDQS blends unit dual quaternions instead of matrices. For a rotation, "
          "vertices whose influences rotate differently differ by design (DQS keeps volume: no candy-wrapper "
          "collapse), by 1-5 % of the diagonal. A translation or a dilation adds no relative rotation between "
          "influences, and there DQS (with Kavan's separate scale blend) equals LBS: the remaining 1e-9 comes "
          "from float32 noise in the files' bind matrices, which DQS splits into rotation and stretch. Fox's "
          "head vertices have a single influence, so all three agree.")

if __name__ == "__main__":
    main()
