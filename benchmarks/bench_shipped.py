"""The kernels shipped with the package (compiled for a portable x86-64 CPU) against the same kernels
compiled by numba on this machine: skin, cut, a tear stroke and a drill, in one run.

    python -m benchmarks.bench_shipped [--repeat 30] [--rounds 3] [--rings 200]

Fresh interpreters, alternating: *host* with ``CGASKIN_SHIPPED_KERNELS=0`` (numba compiles every kernel
for this CPU, SIMD extensions and all, in the first round, into a cache the later rounds load) and
*shipped* (an empty ``NUMBA_CACHE_DIR`` every round: the kernels load from ``cgaskin/_kernels``, each
for the best CPU level this machine runs). Each reports what compiled and what loaded, the seconds of
its first operation from the process's start, the median thread CPU time of each operation (on one
thread, ``NUMBA_NUM_THREADS=1``: the machine is shared, and CPU time leaves out time another process
took), and a digest of every output. The table gives shipped / host speed (> 1: the shipped code is
faster); the outputs must be equal bit for bit. The rig: the built-in capsule arm with ``--rings``
rings of 256 vertices per bone.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

from ._report import benchmark_parser, writes_tables
from ._timing import print_table

# in each child: build the rig, time the operations, print counts, medians and digests (one JSON line)
_CHILD = """
import hashlib, json, statistics, sys, time
start = time.perf_counter()
from numba.core import event
compiles = []

class Recorder(event.Listener):
    def on_start(self, ev):
        compiles.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Recorder())
import numpy as np
import cgaskin
from cgaskin._shared import shipped

repeat, rings = int(sys.argv[1]), int(sys.argv[2])
rig = cgaskin.capsule_arm(rings_per_segment=rings, segments_around=256)
pose = rig.pose("wave", 0.7)
blade = lambda x: ([x, 0.05, 1.0], [x, 0.05, 0.0])
mesh = lambda *rigs: [array for r in rigs for array in (r.vertices, r.faces)]      # (the outputs compared)
operations = {
    "skin": lambda: [cgaskin.skin(rig, pose)],
    "cut": lambda: mesh(*cgaskin.cut(rig, [1, 0.2, 0], [1.5, 0, 0])),
    "tear stroke": lambda: mesh(cgaskin.tear(rig, blade(1.0), blade(1.3), opening=0.01)),
    "drill": lambda: mesh(cgaskin.drill(rig, [1.4, 0.0, -1.0], [1.4, 0.0, 1.0], 0.1)),
}
digests, medians, first = {}, {}, None
for name, operation in operations.items():
    outputs = operation()                      # (the first call: loads or compiles its kernels)
    first = first or time.perf_counter() - start
    digests[name] = hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in outputs)).hexdigest()
    samples = []
    for _ in range(repeat):
        began = time.thread_time()
        operation()
        samples.append(time.thread_time() - began)
    medians[name] = statistics.median(samples)
print("@@" + json.dumps({"compiles": len(compiles), "compiled": sorted(set(compiles)),
                        "loads": sum(shipped.LOADED.values()), "first": first, "medians": medians,
                        "digests": digests, "vertices": len(rig.vertices), "faces": len(rig.faces)}))
"""


def run(shipped: bool, repeat: int, rings: int, cache: str) -> dict:
    """What one fresh interpreter measured (numba's cache ``cache``; the shipped kernels on or off)."""
    env = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_")}
    # one thread: CPU time then measures all the work (skin's blend loop is a prange above 1e5 vertices)
    env.update(NUMBA_CACHE_DIR=cache, CGASKIN_SHIPPED_KERNELS="1" if shipped else "0", NUMBA_NUM_THREADS="1")
    done = subprocess.run([sys.executable, "-c", _CHILD, str(repeat), str(rings)], env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(next(line for line in done.stdout.splitlines() if line.startswith("@@"))[2:])


@writes_tables
def main(argv=None):
    parser = benchmark_parser(__doc__)
    parser.add_argument("--repeat", type=int, default=30, help="timed calls per operation (median)")
    parser.add_argument("--rounds", type=int, default=3, help="host and shipped processes, alternating")
    parser.add_argument("--rings", type=int, default=200, help="rings of 256 vertices per bone of the capsule arm")
    args = parser.parse_args(argv)
    hosts, shipped = [], []
    with tempfile.TemporaryDirectory() as host_cache:       # (the host's kernels compile in its first round)
        for _ in range(args.rounds):
            hosts.append(run(False, args.repeat, args.rings, host_cache))
            with tempfile.TemporaryDirectory() as empty:
                shipped.append(run(True, args.repeat, args.rings, empty))
    for label, result in (("host, first round", hosts[0]), ("shipped, every round", shipped[0])):
        print(f"{label}: {result['compiles']} compiles, {result['loads']} kernels loaded from the shipped layer; "
              f"first operation {result['first']:.1f} s from the process's start")
    if any(result["compiles"] for result in shipped):
        print(f"  compiled with the shipped kernels (not among them): {', '.join(shipped[0]['compiled'])}")
    rows = []
    for name in hosts[0]["medians"]:
        host_ms = 1e3 * statistics.median(result["medians"][name] for result in hosts)
        shipped_ms = 1e3 * statistics.median(result["medians"][name] for result in shipped)
        same = all(result["digests"][name] == hosts[0]["digests"][name] for result in hosts + shipped)
        rows.append([name, host_ms, shipped_ms, host_ms / shipped_ms, "yes" if same else "NO"])
    print_table(f"shipped against host-compiled kernels: capsule arm, {hosts[0]['vertices']} vertices, "
                f"{hosts[0]['faces']} faces; thread CPU ms, median of {args.rounds} alternating rounds' medians "
                f"of {args.repeat} calls", ["operation", "host ms", "shipped ms", "shipped speed", "same output"], rows)


if __name__ == "__main__":
    main()
