"""GLSL skinning shaders (#version 430) on the kernels ``versor_to_affine`` and ``affine_point``: the
two stages of generated/skinning.py (per bone, then per vertex), in double and in float, and a vertex
shader that skins in the vertex stage.

<prefix>_skin_bones.comp      per bone: versors (B, 12) -> affines (B, 12), one invocation per bone
<prefix>_skin.comp            per vertex: out[i] = (Σ_k w[i,k] affines[joints[i,k]]) applied to rest[i]
<prefix>_skin_bones_f32.comp  the same in float (no fp64 needed)
<prefix>_skin_f32.comp
<prefix>_skin.vert            a vertex shader (float) whose <prefix>_skin_vertex(position, joints,
                              weights) blends the affines of an SSBO; captured by transform feedback
                              or used for gl_Position
<prefix>_skin_webgl.glsl      GLSL ES 3.00 (WebGL2) functions for a page's vertex shader: each bone's
                              versor -> affine in the shader, then the blend (``webgl_chunk``)

Storage buffers are std430 arrays of scalars (flat: std430's vec3[] has a 16-byte stride), sizes in a
std140 uniform block at binding 0 (SPIR-V needs loose uniforms in a block). Work groups are 64 wide; the
blend reads its vertex index from x and y (dispatch (min(g, 65535), ceil(g / 65535)) groups with
g = ceil(n / 64)) so that meshes beyond 4M vertices need no second dispatch. Bad input is skipped as the
numba loop skips it: a joint index outside [0, B) is not read; the counts the numba loop returns (bad
joints, negative or NaN weights, non-finite results) are added atomically to ``counts[3]`` (zero it
before the dispatch; the atomics run only on bad input). The vertex shader skips bad joints without
counting.
"""
from __future__ import annotations

from ..ir import CodegenError
from .glsl_kernels import comment, dialect, kernel_function
from .glsl_math import library

LOCAL_SIZE = 64


def _functions(by_name, prefix: str, double: bool, names) -> str:
    real = "double" if double else "float"
    d = dialect(prefix, double)
    text = "\n".join(kernel_function(by_name[n], prefix, d, real) for n in names)
    return (library(prefix, double) + "\n" + text) if f"{prefix}_lib_" in text else text


def bones_shader(by_name, prefix: str, header, double: bool) -> str:
    real = "double" if double else "float"
    return f"""#version 430
{comment(header, f"cgaskin skinning, stage 1 of 2 ({real}): one invocation per bone, versor -> affine")}
// versors: (B, 12) blade coefficients (generated/layout.py order); affines: (B, 12) row-major 3x4.
// Dispatch ceil(B / {LOCAL_SIZE}) groups; then {prefix}_skin{'' if double else '_f32'}.comp blends affines.
layout(local_size_x = {LOCAL_SIZE}) in;
layout(std430, binding = 0) readonly buffer Versors {{ {real} versors[]; }};
layout(std430, binding = 1) writeonly buffer Affines {{ {real} affines[]; }};
layout(std140, binding = 0) uniform BoneSizes {{ uint bone_count; }};

{_functions(by_name, prefix, double, ["versor_to_affine"])}
void main() {{
    uint b = gl_GlobalInvocationID.x;
    if (b >= bone_count) return;
    {real} v[12];
    for (uint c = 0u; c < 12u; c++) v[c] = versors[b * 12u + c];
    {real} a[12];
    {prefix}_versor_to_affine(v, a);
    for (uint c = 0u; c < 12u; c++) affines[b * 12u + c] = a[c];
}}
"""


def blend_shader(by_name, prefix: str, header, double: bool) -> str:
    real = "double" if double else "float"
    zero = "0.0lf" if double else "0.0"
    return f"""#version 430
{comment(header, f"cgaskin skinning, stage 2 of 2 ({real}): one invocation per vertex")}
// out[i] = (sum_k weights[i,k] affines[joints[i,k]]) applied to rest[i], as generated/skinning.py:
// rest (n, 3), joints (n, k) int, weights (n, k), affines (B, 12) from the bones stage or any other
// source, skinned (n, 3). counts: bad joint indices (skipped, never read), negative or NaN weights,
// vertices with a non-finite result (atomic adds; zero them before the dispatch).
// Dispatch (min(g, 65535), ceil(g / 65535)) groups, g = ceil(n / {LOCAL_SIZE}).
layout(local_size_x = {LOCAL_SIZE}) in;
layout(std430, binding = 0) readonly buffer Rest {{ {real} rest[]; }};
layout(std430, binding = 1) readonly buffer Joints {{ int joints[]; }};
layout(std430, binding = 2) readonly buffer Weights {{ {real} weights[]; }};
layout(std430, binding = 3) readonly buffer Affines {{ {real} affines[]; }};
layout(std430, binding = 4) writeonly buffer Skinned {{ {real} skinned[]; }};
layout(std430, binding = 5) buffer Counts {{ uint counts[3]; }};
layout(std140, binding = 0) uniform SkinSizes {{ uint vertex_count; uint influences; uint bone_count; }};

{_functions(by_name, prefix, double, ["affine_point"])}
void main() {{
    uint i = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * {LOCAL_SIZE}u) + gl_GlobalInvocationID.x;
    if (i >= vertex_count) return;
    {real} a[12];
    for (uint c = 0u; c < 12u; c++) a[c] = {zero};
    for (uint k = 0u; k < influences; k++) {{
        {real} w = weights[i * influences + k];
        if (isnan(w) || w < {zero}) atomicAdd(counts[1], 1u);
        int b = joints[i * influences + k];
        if (b < 0 || uint(b) >= bone_count) {{
            atomicAdd(counts[0], 1u);
            continue;
        }}
        for (uint c = 0u; c < 12u; c++) a[c] += w * affines[uint(b) * 12u + c];
    }}
    {real} x[3] = {real}[3](rest[3u * i], rest[3u * i + 1u], rest[3u * i + 2u]);
    {real} r[3];
    {prefix}_affine_point(a, x, r);
    for (uint c = 0u; c < 3u; c++) skinned[3u * i + c] = r[c];
    if (any(isnan({'dvec3' if double else 'vec3'}(r[0], r[1], r[2]))) || any(isinf({'dvec3' if double else 'vec3'}(r[0], r[1], r[2]))))
        atomicAdd(counts[2], 1u);
}}
"""


def vertex_shader(by_name, prefix: str, header) -> str:
    return f"""#version 430
{comment(header, "cgaskin skinning in the vertex stage (float): a vertex shader to use or copy from")}
// {prefix}_skin_vertex(position, joints, weights) blends the (B, 12) row-major 3x4 affines of the SSBO
// at binding 0 (from {prefix}_skin_bones_f32.comp, or pose.bone_affines() uploaded as float) and
// applies the blend to position; joints >= bone_count are skipped (not read). The skinned position
// is written to skinned_position (location 0; for transform feedback) and, through view_projection,
// to gl_Position. glTF's JOINTS_0 (unsigned byte/short) binds as uvec4 with glVertexAttribIPointer.
layout(location = 0) in vec3 position;
layout(location = 1) in uvec4 joints;
layout(location = 2) in vec4 weights;
layout(std430, binding = 0) readonly buffer Affines {{ float affines[]; }};
layout(std140, binding = 0) uniform Skinning {{ mat4 view_projection; uint bone_count; }};
layout(location = 0) out vec3 skinned_position;

{_functions(by_name, prefix, False, ["affine_point"])}
vec3 {prefix}_skin_vertex(vec3 position, uvec4 joints, vec4 weights) {{
    float a[12];
    for (uint c = 0u; c < 12u; c++) a[c] = 0.0;
    for (int k = 0; k < 4; k++) {{
        if (joints[k] >= bone_count) continue;
        for (uint c = 0u; c < 12u; c++) a[c] += weights[k] * affines[joints[k] * 12u + c];
    }}
    float x[3] = float[3](position.x, position.y, position.z);
    float r[3];
    {prefix}_affine_point(a, x, r);
    return vec3(r[0], r[1], r[2]);
}}

void main() {{
    skinned_position = {prefix}_skin_vertex(position, joints, weights);
    gl_Position = view_projection * vec4(skinned_position, 1.0);
}}
"""


def webgl_chunk(by_name, prefix: str, header) -> str:
    """GLSL ES 3.00 (WebGL2: no SSBO, no double, no compute) for a page's vertex shader. The bones come in
    a float RGBA texture, 6 texels a bone: the bone's global versor (12 floats, blade order), then a
    3x4 map R applied first (row-major: a bone's inverse bind matrix, and whatever the page folds in;
    for a bone whose global is not a similarity the page gives the identity versor and its whole map as
    R). ``<prefix>_versor_to_affine`` (float) runs per influence, as the compute shaders do per bone."""
    return f"""{comment(header, "cgaskin skinning for WebGL2 (GLSL ES 3.00, float): versors in, blended 3x4 maps out")}
// No #version line: paste or inject after the shader's own (#version 300 es, precision highp float).
// {prefix}_bones: (bone_count * 6) RGBA float texels, row-major over the texture's width: per bone b, texels
// 6b..6b+2 hold its versor V (blade order of generated/layout.py), 6b+3..6b+5 a 3x4 map R (row-major).
// Bone b moves a point p to versor_to_affine(V) applied to R p. {prefix}_blend(joints, weights, a) sums
// weights[k] times bone joints[k]'s map into a[12] (joints outside [0, bone_count) are skipped, not
// read); {prefix}_apply_point / {prefix}_apply_direction apply it to a point / a direction.
uniform highp sampler2D {prefix}_bones;
uniform int {prefix}_bone_count;

{_functions(by_name, prefix, False, ["versor_to_affine", "affine_point"])}
vec4 {prefix}_bone_texel(int i) {{
    int width = textureSize({prefix}_bones, 0).x;
    return texelFetch({prefix}_bones, ivec2(i % width, i / width), 0);
}}

void {prefix}_bone_map(int b, out float a[12]) {{
    float v[12];
    float r[12];
    for (int t = 0; t < 3; t++) {{
        vec4 versor = {prefix}_bone_texel(6 * b + t);
        vec4 map = {prefix}_bone_texel(6 * b + 3 + t);
        for (int c = 0; c < 4; c++) {{
            v[4 * t + c] = versor[c];
            r[4 * t + c] = map[c];
        }}
    }}
    float l[12];
    {prefix}_versor_to_affine(v, l);
    for (int i = 0; i < 3; i++) {{
        for (int j = 0; j < 4; j++) {{
            float s = j == 3 ? l[4 * i + 3] : 0.0;
            for (int k = 0; k < 3; k++) s += l[4 * i + k] * r[4 * k + j];
            a[4 * i + j] = s;
        }}
    }}
}}

void {prefix}_blend(vec4 joints, vec4 weights, out float a[12]) {{
    for (int c = 0; c < 12; c++) a[c] = 0.0;
    for (int k = 0; k < 4; k++) {{
        int b = int(joints[k]);
        if (b < 0 || b >= {prefix}_bone_count || weights[k] == 0.0) continue;
        float m[12];
        {prefix}_bone_map(b, m);
        for (int c = 0; c < 12; c++) a[c] += weights[k] * m[c];
    }}
}}

vec3 {prefix}_apply_point(float a[12], vec3 p) {{
    float x[3] = float[3](p.x, p.y, p.z);
    float r[3];
    {prefix}_affine_point(a, x, r);
    return vec3(r[0], r[1], r[2]);
}}

vec3 {prefix}_apply_direction(float a[12], vec3 d) {{
    return vec3(a[0] * d.x + a[1] * d.y + a[2] * d.z, a[4] * d.x + a[5] * d.y + a[6] * d.z,
                a[8] * d.x + a[9] * d.y + a[10] * d.z);
}}
"""


def skin_files(kernels, prefix: str, header) -> dict:
    """{file name: text} of the skinning shaders (module docstring)."""
    by_name = {k.name: k for k in kernels}
    missing = [n for n in ("versor_to_affine", "affine_point") if n not in by_name]
    if missing:
        raise CodegenError(f"GLSL skinning needs the kernels {', '.join(missing)}")
    return {f"{prefix}_skin_bones.comp": bones_shader(by_name, prefix, header, True),
            f"{prefix}_skin.comp": blend_shader(by_name, prefix, header, True),
            f"{prefix}_skin_bones_f32.comp": bones_shader(by_name, prefix, header, False),
            f"{prefix}_skin_f32.comp": blend_shader(by_name, prefix, header, False),
            f"{prefix}_skin.vert": vertex_shader(by_name, prefix, header),
            f"{prefix}_skin_webgl.glsl": webgl_chunk(by_name, prefix, header)}
