"""The DynamicBVH of an editing session against a static TriangleBVH, on a 1.58M-face capsule.

    python -m benchmarks.bench_dynamic_bvh

Prints: build time and tree memory of both; first_hit per query on 20k random segments;
faces_near_plane over a slab of ~2000 faces; the median and p90 of one stroke's edits (remove 30
faces, insert 3 pieces of each, move 40) over a 300-stroke incision, its degradation and rebuilds,
and first_hit against a rebuilt tree; then strokes at random places that also move faces ~0.02, with
the degradation and the first_hit ratio to a rebuilt tree (what ``dynamic_bvh.REBUILD_AT`` is set
by). The BVH reads the bench's mesh arrays, which grow like a session's (spare room, doubled when
full).
"""
from __future__ import annotations

import time

import numpy as np

import cgaskin.surgery.dynamic_bvh as dyn
from cgaskin import TriangleBVH, capsule_arm
from cgaskin._shared.jit import kernel
from cgaskin.surgery.bvh import _first_hit
from cgaskin.surgery.dynamic_bvh import DynamicBVH

from ._report import benchmark_parser, writes_tables


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


class _Mesh:
    """The arrays a DynamicBVH reads, as an editing session keeps them: positions and faces (rows by
    face id) with spare room, grown by doubling; ``view`` gives the rows in use."""

    def __init__(self, points, faces):
        self.positions, self.n = np.concatenate((points, np.empty_like(points))), len(points)
        self.faces, self.m = np.concatenate((faces, np.empty_like(faces))), len(faces)

    def view(self):
        return self.positions[:self.n], self.faces[:self.m]

    def add(self, points, faces):
        """Append vertices (p, 3) and faces (k, 3) (their vertex ids); returns the new face ids."""
        for name, count, rows in (("positions", "n", points), ("faces", "m", faces)):
            buffer, used = getattr(self, name), getattr(self, count)
            if used + len(rows) > len(buffer):
                grown = np.empty((2 * (used + len(rows)), 3), buffer.dtype)
                grown[:used] = buffer[:used]
                setattr(self, name, grown)
            getattr(self, name)[used:used + len(rows)] = rows
            setattr(self, count, used + len(rows))
        return np.arange(self.m - len(faces), self.m)


def _stroke(bvh, mesh, centre, rng, move):
    """Remove the ~30 faces nearest ``centre``, insert 3 pieces of each (fanned to its centroid), move
    40 faces nearby by ``move`` (each gets new corners: its own, each shifted ~``move``); returns the
    seconds of the three calls."""
    r = 0.002
    while len(near := bvh.faces_in_box(centre - r, centre + r)) < 30:
        r *= 1.5
    positions, faces = mesh.view()
    removed = near[np.argsort(np.abs(positions[faces[near]].mean(axis=1) - centre).sum(axis=1))[:30]]
    corners = faces[removed]
    middle = mesh.n + np.arange(len(removed))
    pieces = np.concatenate([np.stack([corners[:, j], corners[:, (j + 1) % 3], middle], axis=1) for j in range(3)])
    ids = mesh.add(positions[corners].mean(axis=1), pieces)
    moved = np.setdiff1d(bvh.faces_in_box(centre - 3 * r, centre + 3 * r), removed)[:40]
    positions, faces = mesh.view()
    shifted = positions[faces[moved]] + rng.normal(0, move, (len(moved), 3, 3))
    mesh.add(shifted.reshape(-1, 3), np.empty((0, 3), np.int64))
    positions, faces = mesh.view()
    faces[moved] = np.arange(mesh.n - 3 * len(moved), mesh.n).reshape(-1, 3)
    start = time.perf_counter()
    bvh.remove(removed)
    bvh.insert(ids, positions, faces)
    bvh.update(moved, positions, faces)
    return time.perf_counter() - start


@writes_tables
def main(argv=None):
    benchmark_parser(__doc__).parse_args(argv)
    rig = capsule_arm(rings_per_segment=850, segments_around=294)
    points, faces = np.asarray(rig.vertices), np.asarray(rig.faces)
    start = time.perf_counter()
    static = TriangleBVH(points, faces)
    t_static = time.perf_counter() - start
    mesh = _Mesh(points, faces)
    start = time.perf_counter()
    bvh = DynamicBVH(*mesh.view())
    t_dyn = time.perf_counter() - start
    # the trees' own arrays (the static one's copies of positions and faces, 48 bytes a face, apart)
    mem_static = sum(x.nbytes for x in static._arrays[:7])
    mem_dyn = bvh.nbytes
    print(f"\n{len(faces)} faces: build static {t_static:.2f} s, dynamic {t_dyn:.2f} s; tree memory static "
          f"{mem_static / 1e6:.0f} MB, dynamic {mem_dyn / 1e6:.0f} MB ({mem_dyn / mem_static:.2f}x; "
          f"{mem_dyn / len(faces):.0f} bytes a face)")
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
    _stroke(bvh, mesh, np.array([0.3, 0.0, 0.25]), rng, 1e-5)    # compiles
    times = [_stroke(bvh, mesh, np.array([0.5 + 2.0 * i / 300, 0.0, 0.25]), rng, 1e-5) for i in range(300)]
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
                _stroke(bvh, mesh, mesh.positions[rng.integers(mesh.n)], rng, 0.02)
                done += 1
            q_now, degradation, state = per_query(), bvh.degradation, (bvh._st, bvh._sah0)
            bvh.rebuild()
            q_fresh = per_query()
            print(f"{n} random strokes moving 40 faces by ~0.02: degradation {degradation:.2f}, "
                  f"first_hit {q_now:.2f} us vs {q_fresh:.2f} us rebuilt ({q_now / q_fresh:.2f}x)")
            bvh._st, bvh._sah0 = state
    finally:
        dyn.REBUILD_AT = saved


if __name__ == "__main__":
    main()
