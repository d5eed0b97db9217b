"""Skinning throughput: the hoisted CGA path against matrix baselines, in one process.

    python -m benchmarks.bench_skinning [--vertices 1000000] [--bones 32]

Rows: cgaskin.skin_vertices (serial and 2-thread prange, float64 weights/int64 joints and compact
float32 weights/uint8 joints), a hand-written numba 3x4 LBS (the bar to beat), numpy einsum LBS, and
the memory-traffic bound implied by a measured copy bandwidth. Medians of repeated runs; ratios are
against the hand-written numba LBS measured in the same run.
"""
from __future__ import annotations


import numba
import numpy as np
from numba import njit, prange

import cgaskin
from cgaskin import versor
from cgaskin.animation.skinning import bone_affines

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table


@njit(cache=True)
def handwritten_lbs(rest, joints, weights, mats, out):
    """Plain 3x4 matrix LBS written by hand: blend the bone matrices in scalars, then apply."""
    for i in range(rest.shape[0]):
        m0 = m1 = m2 = m3 = m4 = m5 = m6 = m7 = m8 = m9 = m10 = m11 = 0.0
        for k in range(joints.shape[1]):
            w = weights[i, k]
            a = mats[joints[i, k]]
            m0 += w * a[0]
            m1 += w * a[1]
            m2 += w * a[2]
            m3 += w * a[3]
            m4 += w * a[4]
            m5 += w * a[5]
            m6 += w * a[6]
            m7 += w * a[7]
            m8 += w * a[8]
            m9 += w * a[9]
            m10 += w * a[10]
            m11 += w * a[11]
        x, y, z = rest[i, 0], rest[i, 1], rest[i, 2]
        out[i, 0] = m0 * x + m1 * y + m2 * z + m3
        out[i, 1] = m4 * x + m5 * y + m6 * z + m7
        out[i, 2] = m8 * x + m9 * y + m10 * z + m11


@njit(cache=True, parallel=True)
def copy_kernel(src, dst):
    for i in prange(src.shape[0]):
        dst[i] = src[i]


def einsum_lbs(rest, joints, weights, mats):
    blended = np.einsum("nk,nkc->nc", weights, mats[joints])
    m = blended.reshape(-1, 3, 4)
    return np.einsum("nij,nj->ni", m[:, :, :3], rest) + m[:, :, 3]


def make_problem(n, n_bones, seed=0):
    rng = np.random.default_rng(seed)
    rest = rng.normal(size=(n, 3)) * 10
    joints = rng.integers(0, n_bones, (n, 4))
    weights = rng.random((n, 4))
    weights /= weights.sum(1, keepdims=True)
    versors = versor.compose(
        versor.motor(rng.normal(size=(n_bones, 3)), rng.uniform(-np.pi, np.pi, n_bones), rng.normal(size=(n_bones, 3))),
        versor.dilator(rng.uniform(0.5, 2.0, n_bones)))
    return rest, joints, weights, versors


@writes_tables
def main(argv=None):
    ap = benchmark_parser(__doc__)
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--bones", type=int, default=32)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    n = args.vertices
    rest, joints, weights, versors = make_problem(n, args.bones)
    mats = np.ascontiguousarray(versor.to_matrix(versors)[:, :3, :].reshape(-1, 12))
    out = np.empty_like(rest)
    w32, j8 = weights.astype(np.float32), joints.astype(np.uint8)

    ref = einsum_lbs(rest, joints, weights, mats)
    err = np.abs(cgaskin.skin_vertices(rest, joints, weights, versors) - ref).max() / np.abs(ref).max()

    rows = []
    t_hand = median_seconds(lambda: handwritten_lbs(rest, joints, weights, mats, out), args.repeat)
    cases = [
        ("cgaskin.skin_vertices serial", lambda: cgaskin.skin_vertices(rest, joints, weights, versors, parallel=False)),
        ("cgaskin.skin_vertices serial, out= reused", lambda: cgaskin.skin_vertices(rest, joints, weights, versors, parallel=False, out=out)),
        ("cgaskin.skin_vertices serial f32 w/u8 j", lambda: cgaskin.skin_vertices(rest, j8, w32, versors, parallel=False)),
        (f"cgaskin.skin_vertices prange ({numba.get_num_threads()} thr)", lambda: cgaskin.skin_vertices(rest, joints, weights, versors, parallel=True)),
        (f"cgaskin.skin_vertices prange f32 w/u8 j", lambda: cgaskin.skin_vertices(rest, j8, w32, versors, parallel=True)),
        ("hand-written numba 3x4 LBS serial", None),
        ("numpy einsum LBS", lambda: einsum_lbs(rest, joints, weights, mats)),
    ]
    for name, fn in cases:
        t = t_hand if fn is None else median_seconds(fn, args.repeat if "einsum" not in name else 3)
        rows.append([name, t * 1e3, n / t, t_hand / t])

    # memory-traffic bound: bytes each vertex must move (rest in, out, joints, weights) / copy bandwidth
    big = np.ones(50_000_000)
    dst = np.empty_like(big)
    t_copy = median_seconds(lambda: copy_kernel(big, dst), 5)
    bandwidth = 2 * big.nbytes / t_copy
    per_vertex = rest.itemsize * 6 + joints.itemsize * 4 + weights.itemsize * 4
    rows.append([f"bandwidth bound ({per_vertex} B/vertex, {bandwidth / 1e9:.1f} GB/s)", per_vertex * n / bandwidth * 1e3,
                 bandwidth / per_vertex, t_hand * bandwidth / per_vertex / n])
    print_table(f"Skinning {n} vertices x 4 influences x {args.bones} bones (median of {args.repeat}; "
                f"max relative error vs einsum LBS {err:.1e})",
                ["method", "ms", "vertices/s", "x hand-written"], rows)

    # per-frame cost of the per-bone half
    t_aff = median_seconds(lambda: bone_affines(versors), 7, min_time=0.05)
    print(f"\nper-bone versor_to_affine for {args.bones} bones: {t_aff * 1e6:.1f} us")

    # crossover between serial and prange
    sizes = [1_000, 3_000, 10_000, 30_000, 100_000]
    cross = []
    for m in sizes:
        r, j, w, v = rest[:m], joints[:m], weights[:m], versors
        ts = median_seconds(lambda: cgaskin.skin_vertices(r, j, w, v, parallel=False), 7, min_time=0.05)
        tp = median_seconds(lambda: cgaskin.skin_vertices(r, j, w, v, parallel=True), 7, min_time=0.05)
        cross.append([m, ts * 1e3, tp * 1e3, ts / tp])
    print_table("serial vs prange crossover", ["vertices", "serial ms", "prange ms", "speedup"], cross)


if __name__ == "__main__":
    main()
