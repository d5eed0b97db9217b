"""The DynamicBVH of an editing session against a static TriangleBVH, on a 1.58M-face capsule.

    python -m benchmarks.bench_dynamic_bvh

Prints: build time and memory of both; first_hit per query on 20k random segments; faces_near_plane
over a slab of ~2000 faces; the median and p90 of one stroke's edits (remove 30 faces, insert 3
pieces of each, move 40) over a 300-stroke incision, its degradation and rebuilds, and first_hit
against a rebuilt tree; then strokes at random places that also move faces ~0.02, with the
degradation and the first_hit ratio to a rebuilt tree (what ``dynamic_bvh.REBUILD_AT`` is set by).
"""
from __future__ import annotations

import time

import numpy as np

import cgaskin.surgery.dynamic_bvh as dyn
from cgaskin import TriangleBVH, capsule_arm
from cgaskin._shared.jit import kernel
from cgaskin.surgery.bvh import _first_hit
from cgaskin.surgery.dynamic_bvh import DynamicBVH


@kernel()
def _query_loop(arrays, a, b):
    """first_hit on every segment a[i] -> b[i] (the same traversal reads either tree's arrays)."""
    n = 0
    for i in range(a.shape[0]):
        n += _first_hit(arrays, a[i], b[i])[0] >= 0
    return n


def _best(call, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def _stroke(bvh, centre, next_id, rng, move):
    """Remove the ~30 faces nearest ``centre``, insert 3 pieces of each, move 40 faces nearby by
    ``move``; returns (seconds of the three calls, next free id)."""
    r = 0.002
    while len(near := bvh.faces_in_box(centre - r, centre + r)) < 30:
        r *= 1.5
    centres = np.array([bvh.triangle(f).mean(axis=0) for f in near])
    removed = near[np.argsort(np.abs(centres - centre).sum(axis=1))[:30]]
    c = np.array([bvh.triangle(f) for f in removed])
    m = c.mean(axis=1)
    pieces = np.concatenate([np.stack([c[:, j], c[:, (j + 1) % 3], m], axis=1) for j in range(3)])
    moved = np.setdiff1d(bvh.faces_in_box(centre - 3 * r, centre + 3 * r), removed)[:40]
    corners = np.array([bvh.triangle(f) for f in moved]) + rng.normal(0, move, (len(moved), 3, 3))
    ids = np.arange(next_id, next_id + len(pieces))
    start = time.perf_counter()
    bvh.remove(removed)
    bvh.insert(ids, pieces)
    bvh.update(moved, corners)
    return time.perf_counter() - start, next_id + len(pieces)


def main():
    rig = capsule_arm(rings_per_segment=850, segments_around=294)
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    start = time.perf_counter()
    static = TriangleBVH(points, faces)
    t_static = time.perf_counter() - start
    start = time.perf_counter()
    bvh = DynamicBVH(points, faces)
    t_dyn = time.perf_counter() - start
    mem_static = sum(x.nbytes for x in static._arrays) + static._slot.nbytes
    mem_dyn = sum(x.nbytes for x in bvh._st)
    print(f"\n{len(faces)} faces: build static {t_static:.2f} s, dynamic {t_dyn:.2f} s; memory static "
          f"{mem_static / 1e6:.0f} MB, dynamic {mem_dyn / 1e6:.0f} MB ({mem_dyn / mem_static:.2f}x)")
    rng = np.random.default_rng(1)
    lo, hi = points.min(axis=0), points.max(axis=0)
    a, b = rng.uniform(lo, hi, (20000, 3)), rng.uniform(lo, hi, (20000, 3))
    _query_loop(bvh.arrays, a, b), _query_loop(tuple(static._arrays), a, b)

    def per_query():
        return _best(lambda: _query_loop(bvh.arrays, a, b)) / len(a) * 1e6
    q_static = _best(lambda: _query_loop(tuple(static._arrays), a, b)) / len(a) * 1e6
    q_dyn = per_query()
    print(f"first_hit: static {q_static:.2f} us, dynamic {q_dyn:.2f} us ({q_dyn / q_static:.2f}x)")
    plane = (lo - 1, hi + 1, np.array([1.0, 0, 0]), 1.5, 0.0017)
    k = len(bvh.faces_near_plane(*plane))
    print(f"faces_near_plane over {k} faces: {_best(lambda: bvh.faces_near_plane(*plane), 20) * 1e3:.3f} ms")
    next_id = _stroke(bvh, np.array([0.3, 0.0, 0.25]), len(faces), rng, 1e-5)[1]    # compiles
    times = []
    for i in range(300):
        dt, next_id = _stroke(bvh, np.array([0.5 + 2.0 * i / 300, 0.0, 0.25]), next_id, rng, 1e-5)
        times.append(dt)
    q_now = per_query()
    degradation, rebuilds = bvh.degradation, bvh.rebuilds
    bvh.rebuild()
    print(f"incision, 300 strokes: {np.median(times) * 1e3:.3f} ms median, {np.quantile(times, 0.9) * 1e3:.3f}"
          f" ms p90 per stroke; rebuilds {rebuilds}, degradation {degradation:.3f}; first_hit "
          f"{q_now:.2f} us vs {per_query():.2f} us rebuilt")
    dyn.REBUILD_AT, saved = np.inf, dyn.REBUILD_AT
    try:
        done = 0
        for n in (150, 300, 450, 600, 1000, 2000):
            while done < n:
                next_id = _stroke(bvh, points[rng.integers(len(points))], next_id, rng, 0.02)[1]
                done += 1
            q_now, degradation, state = per_query(), bvh.degradation, (bvh._st, bvh._sah0)
            bvh.rebuild()
            q_fresh = per_query()
            print(f"{n} random strokes moving 40 faces by ~0.02: degradation {degradation:.2f}, first_hit "
                  f"{q_now:.2f} us vs {q_fresh:.2f} us rebuilt ({q_now / q_fresh:.2f}x)")
            bvh._st, bvh._sah0 = state
    finally:
        dyn.REBUILD_AT = saved


if __name__ == "__main__":
    main()
