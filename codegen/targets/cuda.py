"""CUDA printers of the kernel IR: numba-cuda (Python) and CUDA C (for nvcc/NVRTC users).

Files (``render``):

``<prefix>_cuda.py`` (numba-cuda; the ``numba-cuda`` package, numba's own CUDA target is deprecated)
    ``<prefix>_k(inputs...)``: every kernel as ``@cuda.jit(device=True)``, the numba printer's body
    (``codegen.printer.print_kernel`` in the Python dialect, ``cuda.cbrt`` for cube roots), returning
    the same tuple (a bare float for one output);
    ``<prefix>_k_batch[blocks, threads](inputs (N, size) or (N,)..., out (N, n_out))``: a ``@cuda.jit``
    grid-stride loop over rows; a uniform input is passed once ((size,) array or a float);
    with ``skinning=True`` also ``<prefix>_bone_affines[...](versors (B, 12), affines (B, 12))``,
    ``<prefix>_skin_blend[...](rest (n, 3), joints (n, k) int, weights (n, k), affines (B, 12),
    out (n, 3), counts (3,) int64)`` (one thread per vertex, grid-stride; ``counts`` gets the numba
    loop's bad joints / bad weights / non-finite results by atomic adds, only when there are any) and
    the host helper ``<prefix>_skin(rest, joints, weights, affines, out, counts, threads=256)`` that
    launches it. (The skinning kernels live in the same module: a second Python module would have to
    import the first by a package path the user chooses.)
``<prefix>.cuh`` (CUDA C, no includes)
    ``__device__ __forceinline__ void <prefix>_k(const double a[12], ..., double out[N])``: the C99
    printer's functions (``codegen.targets.c_kernels.function_source``) with the CUDA qualifier, and
    ``__global__ void <prefix>_k_batch(size_t n_rows, ...)``: the C batch form as a grid-stride loop.
``<prefix>_skin.cuh`` (with ``skinning=True``; includes ``<prefix>.cuh``)
    ``__device__ <prefix>_skin_vertex`` (the C one, joints as ``int``),
    ``__global__ <prefix>_bone_affines_kernel(size_t n_bones, const double *versors, double *affines)``,
    ``__global__ <prefix>_skin_blend_kernel(size_t n, size_t k, const double *rest, const int *joints,
    const double *weights, size_t n_bones, const double *affines, double *out, unsigned long long *counts)``.

Float64 throughout (the kernels' tolerances are float64 ones).
"""
from __future__ import annotations

from dataclasses import replace

from ..expressions import PYTHON
from ..ir import CodegenError
from ..printer import print_kernel, store_rows
from . import c_kernels as c_target
from .c_skinning import require_skinning_kernels, skin_functions

#: the numba printer's Python with CUDA's cube root (numpy's cbrt is not a device function)
NUMBA_CUDA = replace(PYTHON, name="numba-cuda", cbrt="cuda.cbrt({})")


def _cuda_literal(value) -> str:
    text = c_target.c_literal(value)
    # CUDA C has no <math.h> macros without includes: NaN and infinity from their bit patterns
    return {"NAN": 'nan("")', "INFINITY": "__longlong_as_double(0x7ff0000000000000LL)",
            "(-INFINITY)": "__longlong_as_double(0xfff0000000000000LL)"}.get(text, text)


CUDA_C = replace(c_target.C99, name="cuda-c", literal=_cuda_literal, nan='nan("")')
DEVICE = "__device__ __forceinline__"
GRID_STRIDE = ("for (size_t row = blockIdx.x * (size_t)blockDim.x + threadIdx.x; row < n_rows; "
               "row += (size_t)blockDim.x * gridDim.x)")


# -- numba-cuda ----------------------------------------------------------------------------------
def py_batch(kernel, name: str, uniform=()) -> str:
    """``@cuda.jit def name_batch(inputs..., out)``: the device function on every row, grid-stride."""
    args = [i.name for i in kernel.inputs]
    clash = {"row", "out", "start", "stride", "r"} & set(args)
    if clash:
        raise CodegenError(f"{kernel.name}: inputs named {sorted(clash)} would shadow the batch kernel's names")
    n_out = len(kernel.outputs)
    call = f"{name}({', '.join(a if a in uniform else a + '[row]' for a in args)})"
    lines = ["@cuda.jit",
             f"def {name}_batch({', '.join(args)}, out):",
             f'    """``{name}`` on every row: inputs (N, ...) or (N,), out (N, {n_out}); one thread per row'
             + (f"; taken once: {', '.join(uniform)}" if uniform else "") + '."""',
             "    start = cuda.grid(1)",
             "    stride = cuda.gridsize(1)",
             "    for row in range(start, out.shape[0], stride):"]
    lines += store_rows(call, n_out)
    return "\n".join(lines) + "\n"


def py_skinning(prefix: str) -> str:
    """The numba-cuda skinning kernels (generated/skinning.py's loop, one thread per vertex)."""
    zero = "\n".join(f"        a{c} = 0.0" for c in range(12))
    blend = "\n".join(f"            a{c} += w * affines[b, {c}]" for c in range(12))
    store = "\n".join(f"        affines[b, {c}] = r[{c}]" for c in range(12))
    blended = ", ".join(f"a{c}" for c in range(12))
    return f'''\
@cuda.jit
def {prefix}_bone_affines(versors, affines):
    """affines (B, 12) row-major 3x4 of versors (B, 12): versor_to_affine per bone, one thread each."""
    start = cuda.grid(1)
    stride = cuda.gridsize(1)
    for b in range(start, versors.shape[0], stride):
        r = {prefix}_versor_to_affine(versors[b])
{store}


@cuda.jit
def {prefix}_skin_blend(rest, joints, weights, affines, out, counts):
    """out[i] = (sum_k weights[i,k] affines[joints[i,k]]) applied to rest[i], one thread per vertex.

    rest (n, 3) float64, joints (n, k) int, weights (n, k) float, affines (B, 12) float64, out (n, 3)
    written, counts (3,) int64 incremented by: influences with a joint outside [0, B) (skipped before
    it is read), negative or NaN weights (used as given), vertices with a non-finite result.
    """
    n_bones = affines.shape[0]
    start = cuda.grid(1)
    stride = cuda.gridsize(1)
    for i in range(start, rest.shape[0], stride):
{zero}
        for k in range(joints.shape[1]):
            w = weights[i, k]
            if not w >= 0.0:
                cuda.atomic.add(counts, 1, 1)
            b = joints[i, k]
            if b < 0 or b >= n_bones:
                cuda.atomic.add(counts, 0, 1)
                continue
{blend}
        x = {prefix}_affine_point(({blended}), rest[i])
        out[i, 0] = x[0]
        out[i, 1] = x[1]
        out[i, 2] = x[2]
        if not x[0] * 0.0 + x[1] * 0.0 + x[2] * 0.0 == 0.0:    # false for NaN and inf
            cuda.atomic.add(counts, 2, 1)


def {prefix}_skin(rest, joints, weights, affines, out, counts, threads=256):
    """Launch {prefix}_skin_blend over every vertex (device or host arrays; host arrays are copied
    by numba-cuda). ``threads`` per block; enough blocks for one vertex per thread."""
    blocks = max(1, (rest.shape[0] + threads - 1) // threads)
    {prefix}_skin_blend[blocks, threads](rest, joints, weights, affines, out, counts)
'''


def python_module(kernels, prefix: str, header, uniform=None, skinning: bool = False) -> str:
    uniform = uniform or {}
    doc = "\n".join(["numba-cuda device functions and kernels (float64).", "", *header])
    parts = [f'"""{doc}\n"""\n\nimport math  # noqa: F401\n\nimport numpy as np  # noqa: F401\nfrom numba import cuda\n']
    for k in kernels:
        name = f"{prefix}_{k.name}"
        parts.append(print_kernel(k, decorator="@cuda.jit(device=True)", name=name, dialect=NUMBA_CUDA))
        parts.append(py_batch(k, name, uniform.get(k.name, ())))
    if skinning:
        require_skinning_kernels(kernels)
        parts.append(py_skinning(prefix))
    return "\n\n".join(parts)


# -- CUDA C --------------------------------------------------------------------------------------
def cuda_header(kernels, prefix: str, header, uniform=None) -> str:
    c_target.check_prefix(prefix)
    uniform = uniform or {}
    guard = c_target.guard_name(f"{prefix}.cuh")
    lines = [*c_target.comment([*header, "", "CUDA C kernels (float64): __device__ <prefix>_<kernel>(inputs..., out) and",
                                "__global__ <prefix>_<kernel>_batch(n_rows, ...) (grid-stride loop, any launch shape).",
                                "Flat arrays in the blade order of cgaskin's generated/layout.py; 3x4 matrices row-major."]),
             f"#ifndef {guard}", f"#define {guard}", ""]
    for k in kernels:
        name = f"{prefix}_{k.name}"
        lines.append(c_target.function_source(k, name, DEVICE, CUDA_C))
        lines.append(c_target.batch_source(k, name, "__global__", uniform.get(k.name, ()), loop=GRID_STRIDE))
    lines.append(f"#endif /* {guard} */")
    return "\n".join(lines) + "\n"


def cuda_skin_header(kernels, prefix: str, header) -> str:
    require_skinning_kernels(kernels)
    guard = c_target.guard_name(f"{prefix}_skin.cuh")
    loop = "for (size_t {v} = blockIdx.x * (size_t)blockDim.x + threadIdx.x; {v} < {n}; {v} += (size_t)blockDim.x * gridDim.x)"
    lines = [*c_target.comment([*header, "", "CUDA C skinning: per bone <prefix>_bone_affines_kernel, per vertex",
                                "<prefix>_skin_blend_kernel (one thread per vertex, grid-stride)."]),
             f"#ifndef {guard}", f"#define {guard}", "", f'#include "{prefix}.cuh"', "",
             "/* affines (n_bones x 12, row-major 3x4) of versors (n_bones x 12) */",
             f"__global__ void {prefix}_bone_affines_kernel(size_t n_bones, const double *versors, double *affines)",
             "{", f"    {loop.format(v='b', n='n_bones')}",
             f"        {prefix}_versor_to_affine(versors + 12 * b, affines + 12 * b);", "}", "",
             skin_functions(prefix, DEVICE, "int"),
             "/*",
             " * out (n x 3) = rest (n x 3) skinned by joints, weights (n x k, row-major) and affines (n_bones x 12).",
             " * counts[3] (zero it before the launch) gets bad joints, bad weights, non-finite results: one",
             " * atomic add per thread that found any, none on valid input.",
             " */",
             f"__global__ void {prefix}_skin_blend_kernel(size_t n, size_t k, const double *rest, const int *joints,",
             "        const double *weights, size_t n_bones, const double *affines, double *out, unsigned long long *counts)",
             "{",
             "    size_t found[3] = {0, 0, 0};",
             f"    {loop.format(v='i', n='n')}",
             f"        {prefix}_skin_vertex(k, rest + 3 * i, joints + k * i, weights + k * i, n_bones, affines, out + 3 * i, found);",
             "    for (int c = 0; c < 3; ++c)",
             "        if (found[c])",
             "            atomicAdd(counts + c, (unsigned long long)found[c]);",
             "}", "", f"#endif /* {guard} */"]
    return "\n".join(lines) + "\n"


def render(kernels, *, prefix: str, header, uniform=None, skinning: bool = False) -> dict[str, str]:
    """{``<prefix>_cuda.py``, ``<prefix>.cuh``, and with ``skinning`` ``<prefix>_skin.cuh``}."""
    c_target.check_prefix(prefix)
    files = {f"{prefix}_cuda.py": python_module(kernels, prefix, header, uniform, skinning),
             f"{prefix}.cuh": cuda_header(kernels, prefix, header, uniform)}
    if skinning:
        files[f"{prefix}_skin.cuh"] = cuda_skin_header(kernels, prefix, header)
    return files
