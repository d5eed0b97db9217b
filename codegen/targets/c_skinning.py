"""The skinning stages in C (and, with other qualifiers and types, in CUDA C): per bone
``versor_to_affine``, then per vertex the blend of generated/skinning.py.

``<prefix>_skin.h`` (includes ``<prefix>.h``; ``<stdint.h>`` for the joint type):

``void <prefix>_bone_affines(size_t n_bones, const double *versors, double *affines)``
    versors n_bones x 12 (blade order of generated/layout.py) -> affines n_bones x 12 (row-major 3x4).
``<prefix>_skin_counts <prefix>_skin_blend(size_t n, size_t k, const double *rest, const int32_t *joints,
const double *weights, size_t n_bones, const double *affines, double *out)``
    rest n x 3, joints and weights n x k (row-major), affines n_bones x 12, out n x 3 (written):
    out[i] = (sum_j weights[i,j] affines[joints[i,j]]) applied to rest[i]. Returns the counts the numba
    loop returns: influences whose joint is outside [0, n_bones) (skipped, never read), weights that are
    negative or NaN (used as given), vertices whose result is not finite.
``<prefix>_skin_vertex(...)``: one vertex of that loop (what the CUDA kernel runs per thread).
"""
from __future__ import annotations

from ..ir import CodegenError
from .c_kernels import PRECISIONS, comment, check_prefix, guard_name


def require_skinning_kernels(kernels) -> None:
    names = {k.name for k in kernels}
    missing = {"versor_to_affine", "affine_point"} - names
    if missing:
        raise CodegenError(f"skinning needs the kernels {sorted(missing)}, absent from this catalogue")


def skin_functions(prefix: str, qualifier: str, joint: str, real: str = "double") -> str:
    """``<prefix>_skin_vertex`` in C syntax that C99 and CUDA C share (``prefix`` names the kernels it
    calls: ``<prefix>_affine_point``)."""
    zero = "0.0f" if real == "float" else "0.0"
    blend = "\n".join(f"            a[{c}] += w * row[{c}];" for c in range(12))
    return f"""\
/*
 * One vertex of the blend: out3 = (sum_j weights[j] affines[joints[j]]) applied to rest3. Adds to
 * counts[0] the influences whose joint is outside [0, n_bones) (skipped before it is read), to
 * counts[1] the weights that are negative or NaN (used as given), to counts[2] 1 if the result is not
 * finite: what generated/skinning.py's skin_blend returns.
 */
{qualifier} void {prefix}_skin_vertex(size_t k, const {real} *rest3, const {joint} *joints,
        const {real} *weights, size_t n_bones, const {real} *affines, {real} *out3, size_t counts[3])
{{
    {real} a[12] = {{{", ".join([zero] * 12)}}};
    size_t j;
    for (j = 0; j < k; ++j) {{
        const {real} w = weights[j];
        const {joint} b = joints[j];
        if (!(w >= {zero}))
            counts[1] += 1;
        if (b < 0 || (size_t)b >= n_bones) {{
            counts[0] += 1;
            continue;
        }}
        {{
            const {real} *row = affines + 12 * (size_t)b;
{blend}
        }}
    }}
    {prefix}_affine_point(a, rest3, out3);
    if (!(isfinite(out3[0]) && isfinite(out3[1]) && isfinite(out3[2])))
        counts[2] += 1;
}}
"""


def skin_header_source(kernels, prefix: str, header, precision: str = "double") -> str:
    """The text of ``<prefix>_skin.h`` (double) or ``<prefix>_skin_f32.h`` (float: names
    ``<prefix>_f32_...``, including ``<prefix>_f32.h``)."""
    check_prefix(prefix)
    require_skinning_kernels(kernels)
    _, real, infix = PRECISIONS[precision]
    api = f"{prefix.upper()}_API"
    guard = guard_name(f"{prefix}_skin{infix}.h")
    include = f"{prefix}{infix}.h"
    prefix = prefix + infix
    lines = [*comment([*header, "", f"C99 skinning in {real}, two stages: per bone <prefix>_bone_affines (versor_to_affine),",
                       "then per vertex <prefix>_skin_blend (blend the bones' 3x4 maps by the weights, apply once)."]),
             f"#ifndef {guard}", f"#define {guard}", "", "#include <stdint.h>", "", f'#include "{include}"', "",
             "/* what the blend loop found: bad joint indices (skipped), negative/NaN weights, non-finite results */",
             "typedef struct {", "    size_t bad_joints;", "    size_t bad_weights;", "    size_t bad_values;",
             f"}} {prefix}_skin_counts;", "",
             "/* affines (n_bones x 12, row-major 3x4) of versors (n_bones x 12) */",
             f"{api} void {prefix}_bone_affines(size_t n_bones, const {real} *versors, {real} *affines)",
             "{", "    size_t b;", "    for (b = 0; b < n_bones; ++b)",
             f"        {prefix}_versor_to_affine(versors + 12 * b, affines + 12 * b);", "}", "",
             skin_functions(prefix, api, "int32_t", real),
             "/*",
             " * out (n x 3) = rest (n x 3) skinned by joints, weights (n x k, row-major) and affines (n_bones x 12);",
             " * see <prefix>_skin_vertex for the counts it returns (all zero on valid input).",
             " */",
             f"{api} {prefix}_skin_counts {prefix}_skin_blend(size_t n, size_t k, const {real} *rest,",
             f"        const int32_t *joints, const {real} *weights, size_t n_bones, const {real} *affines, {real} *out)",
             "{",
             "    size_t counts[3] = {0, 0, 0};",
             f"    {prefix}_skin_counts result;",
             "    size_t i;",
             "    for (i = 0; i < n; ++i)",
             f"        {prefix}_skin_vertex(k, rest + 3 * i, joints + k * i, weights + k * i, n_bones, affines,",
             "                out + 3 * i, counts);",
             "    result.bad_joints = counts[0];",
             "    result.bad_weights = counts[1];",
             "    result.bad_values = counts[2];",
             "    return result;",
             "}", "",
             f"#endif /* {guard} */"]
    return "\n".join(lines) + "\n"
