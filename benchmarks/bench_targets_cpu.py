"""Skinning throughput of the generated targets against the memory bound, in one process.

    python -m benchmarks.bench_targets_cpu [--vertices 1000000] [--bones 32] [--cuda [--cuda-vertices 10000000]]

Rows: the C99 target's cgaskin_skin_blend (codegen/targets/c.py) compiled -O3 (and -O3 -march=native, and
its float twin cgaskin_f32_skin_blend) and called through cffi on the numpy buffers (no copies), and
cgaskin.skin_affine (the numba loop) serial and prange, on the same
arrays: rest (n, 3) float64, joints (n, 4) int32, weights (n, 4) float64, affines (B, 12), out (n, 3).
The loop moves 96 B per vertex (rest 24 + joints 16 + weights 32 read, out 24 written; the B x 96 B of
affines stay in cache). The memory bound is that traffic at the bandwidth of a copy measured in the
same process (numpy's one-thread copy, and numba's prange copy on every thread); "of bound" is the
bound's time over the method's (1.0 = as fast as the memory allows). With --cuda and a GPU
(numba.cuda.is_available()), the numba-cuda target's skin_blend kernel on the device, against a
device-to-device copy of the same bytes.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

import cgaskin
from cgaskin.animation.skinning import bone_affines

from ._report import benchmark_parser, writes_tables
from ._timing import median_seconds, print_table
from .bench_skinning import make_problem

BYTES_PER_VERTEX = 3 * 8 + 4 * 4 + 4 * 8 + 3 * 8     # rest, joints int32, weights, out
BYTES_PER_VERTEX_F32 = 3 * 4 + 4 * 4 + 4 * 4 + 3 * 4  # the same in float (the float header)


@njit(cache=True, parallel=True)
def parallel_copy(src, dst):
    for i in prange(src.shape[0]):
        dst[i] = src[i]


def builtin_kernels():
    from cgaskin.codegen import catalogue
    return [make() for make in catalogue.KERNELS]


def c_skin_blend(kernels, directory: Path, flags=("-O3",)):
    """The C target's cgaskin_skin_blend and cgaskin_f32_skin_blend, compiled with ``flags`` into a
    shared library: (ffi, lib)."""
    import cffi
    from cgaskin.codegen.targets import c
    for name, text in c.render(kernels, prefix="cgaskin", header=["bench_targets_cpu"], skinning=True).items():
        (directory / name).write_text(text)
    # the header's functions stay static inline (what a C program gets): exported wrappers call them,
    # so the compiler inlines the per-vertex code into the loop (with -fPIC, external definitions of
    # the header's functions would be interposable calls, not inlined: measured ~2x slower)
    wrappers = [f"""{p}_skin_counts bench_{p}_skin_blend(size_t n, size_t k, const {real} *rest, const int32_t *joints,
        const {real} *weights, size_t n_bones, const {real} *affines, {real} *out)
{{
    return {p}_skin_blend(n, k, rest, joints, weights, n_bones, affines, out);
}}
""" for p, real in (("cgaskin", "double"), ("cgaskin_f32", "float"))]
    (directory / "skin.c").write_text('#include "cgaskin_skin.h"\n#include "cgaskin_skin_f32.h"\n\n' + "\n".join(wrappers))
    lib_path = directory / f"libskin{abs(hash(flags))}.so"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Wextra", "-Werror", *flags, "-ffp-contract=off", "-shared", "-fPIC", str(directory / "skin.c"),
                    "-o", str(lib_path), "-lm"], check=True)
    ffi = cffi.FFI()
    for p, real in (("cgaskin", "double"), ("cgaskin_f32", "float")):
        ffi.cdef(f"typedef struct {{ size_t bad_joints; size_t bad_weights; size_t bad_values; }} {p}_skin_counts;\n"
                 f"{p}_skin_counts bench_{p}_skin_blend(size_t n, size_t k, const {real} *rest, const int32_t *joints,"
                 f" const {real} *weights, size_t n_bones, const {real} *affines, {real} *out);")
    return ffi, ffi.dlopen(str(lib_path))


def cpu_table(args, kernels, work: Path) -> None:
    n = args.vertices
    rest, joints, weights, versors = make_problem(n, args.bones)
    joints = np.ascontiguousarray(joints, np.int32)
    affines = bone_affines(versors)
    out_c, out_numba = np.empty_like(rest), np.empty_like(rest)

    rows = []
    for label, flags in (("-O3", ("-O3",)), ("-O3 -march=native", ("-O3", "-march=native"))):
        ffi, lib = c_skin_blend(kernels, work, flags)
        ptr = {name: ffi.from_buffer(t, a) for name, t, a in (
            ("rest", "double[]", rest), ("joints", "int32_t[]", joints), ("weights", "double[]", weights),
            ("affines", "double[]", affines), ("out", "double[]", out_c))}
        call = lambda: lib.bench_cgaskin_skin_blend(n, 4, ptr["rest"], ptr["joints"], ptr["weights"],  # noqa: E731
                                              len(affines), ptr["affines"], ptr["out"])
        rows.append((f"C99 target skin_blend {label} (cffi)", median_seconds(call, args.repeat)))
    f32 = {name: np.ascontiguousarray(a, np.float32) for name, a in (("rest", rest), ("weights", weights),
                                                                       ("affines", affines))}
    out_f32 = np.empty_like(f32["rest"])
    p32 = {name: ffi.from_buffer("float[]", a) for name, a in (*f32.items(), ("out", out_f32))}
    t_f32 = median_seconds(lambda: lib.bench_cgaskin_f32_skin_blend(n, 4, p32["rest"], ptr["joints"], p32["weights"],
                                                               len(affines), p32["affines"], p32["out"]), args.repeat)
    cgaskin.skin_affine(rest, joints, weights, affines, parallel=False, out=out_numba)
    err = np.abs(out_c - out_numba).max() / np.abs(out_numba).max()
    rows.append(("numba skin_affine serial", median_seconds(
        lambda: cgaskin.skin_affine(rest, joints, weights, affines, parallel=False, out=out_numba), args.repeat)))
    rows.append((f"numba skin_affine prange ({numba.get_num_threads()} thr)", median_seconds(
        lambda: cgaskin.skin_affine(rest, joints, weights, affines, parallel=True, out=out_numba), args.repeat)))

    # the same bytes copied: half of them read, half written
    src = np.ones(n * BYTES_PER_VERTEX // 16)
    dst = np.empty_like(src)
    t_copy1 = median_seconds(lambda: np.copyto(dst, src), args.repeat)
    t_copyn = median_seconds(lambda: parallel_copy(src, dst), args.repeat)
    bound = min(t_copy1, t_copyn)
    table = [[name, t * 1e3, n / t, bound / t] for name, t in rows]
    # the float loop moves fewer bytes: its bound is the copy time scaled to them
    table.insert(2, [f"C99 target f32 skin_blend -O3 -march=native ({BYTES_PER_VERTEX_F32} B/vertex)", t_f32 * 1e3,
                     n / t_f32, bound * BYTES_PER_VERTEX_F32 / BYTES_PER_VERTEX / t_f32])
    table.append([f"memory bound, numpy copy (1 thr, {2 * src.nbytes / t_copy1 / 1e9:.1f} GB/s)", t_copy1 * 1e3,
                  n / t_copy1, bound / t_copy1])
    table.append([f"memory bound, prange copy ({numba.get_num_threads()} thr, {2 * src.nbytes / t_copyn / 1e9:.1f} GB/s)",
                  t_copyn * 1e3, n / t_copyn, bound / t_copyn])
    print_table(f"Skinning {n} vertices x 4 influences x {args.bones} bones, {BYTES_PER_VERTEX} B/vertex "
                f"(median of {args.repeat}; C vs numba max relative difference {err:.1e}, "
                f"float C {np.abs(out_f32 - out_numba).max() / np.abs(out_numba).max():.1e})",
                ["method", "ms", "vertices/s", "of bound"], table)


def cuda_table(args, kernels, work: Path) -> None:
    from numba import cuda
    if not cuda.is_available():
        print("\n--cuda: no CUDA GPU here (numba.cuda.is_available() is False); the numba-cuda target is "
              "tested under the simulator (tests/targets/test_cuda.py), not timed")
        return
    from cgaskin.codegen.targets import cuda as cuda_target
    path = work / "cgaskin_cuda.py"
    path.write_text(cuda_target.render(kernels, prefix="cgaskin", header=["bench_targets_cpu"], skinning=True)[path.name])
    spec = importlib.util.spec_from_file_location("cgaskin_cuda_bench", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    n = args.cuda_vertices
    rest, joints, weights, versors = make_problem(n, args.bones)
    joints = np.ascontiguousarray(joints, np.int32)
    affines = bone_affines(versors)
    d = {name: cuda.to_device(a) for name, a in (("rest", rest), ("joints", joints), ("weights", weights),
                                                   ("affines", affines))}
    d_out, d_counts = cuda.device_array_like(rest), cuda.to_device(np.zeros(3, np.int64))
    threads = 256
    blocks = (n + threads - 1) // threads
    launch = lambda: module.cgaskin_skin_blend[blocks, threads](d["rest"], d["joints"], d["weights"],  # noqa: E731
                                                                d["affines"], d_out, d_counts)

    def timed(fn, repeat=args.repeat):
        fn()
        cuda.synchronize()
        samples = []
        for _ in range(repeat):
            start, stop = cuda.event(), cuda.event()
            start.record()
            fn()
            stop.record()
            stop.synchronize()
            samples.append(start.elapsed_time(stop) / 1e3)     # ms
        return float(np.median(samples))

    t_skin = timed(launch)
    ref = cgaskin.skin_affine(rest[:100_000], joints[:100_000], weights[:100_000], affines)
    err = np.abs(d_out.copy_to_host()[:100_000] - ref).max() / np.abs(ref).max()
    src = cuda.to_device(np.ones(n * BYTES_PER_VERTEX // 16))
    dst = cuda.device_array_like(src)
    t_copy = timed(lambda: dst.copy_to_device(src))
    name = getattr(cuda.get_current_device(), "name", "CUDA simulator")
    name = name.decode() if isinstance(name, bytes) else name
    print_table(f"CUDA ({name}): {n} vertices x 4 influences, {BYTES_PER_VERTEX} B/vertex, {threads} threads/block "
                f"(median of {args.repeat}; max relative difference to numba {err:.1e}; counts {d_counts.copy_to_host().tolist()})",
                ["method", "ms", "vertices/s", "of bound"],
                [["numba-cuda target cgaskin_skin_blend", t_skin * 1e3, n / t_skin, t_copy / t_skin],
                 [f"memory bound, device copy ({2 * src.nbytes / t_copy / 1e9:.0f} GB/s)", t_copy * 1e3, n / t_copy, 1.0]])


@writes_tables
def main(argv=None):
    ap = benchmark_parser(__doc__)
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--bones", type=int, default=32)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--cuda", action="store_true", help="also time the numba-cuda kernel on a GPU")
    ap.add_argument("--cuda-vertices", type=int, default=10_000_000)
    ap.add_argument("--no-cpu", action="store_true", help="only the --cuda table")
    args = ap.parse_args(argv)
    start = time.perf_counter()
    kernels = builtin_kernels()
    with tempfile.TemporaryDirectory() as tmp:
        if not args.no_cpu:
            cpu_table(args, kernels, Path(tmp))
        if args.cuda:
            cuda_table(args, kernels, Path(tmp))
    print(f"\n({time.perf_counter() - start:.0f} s)", file=sys.stderr)


if __name__ == "__main__":
    main()
