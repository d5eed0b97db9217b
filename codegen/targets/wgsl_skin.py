"""The WGSL skinning compute shader (``<prefix>_skin.wgsl``), the WebGPU form of
generated/skinning.py: per bone ``versor_to_affine``, then per vertex the blend Σ_k w_k A[joint_k]
and one ``affine_point``."""
from __future__ import annotations

#: invocations per workgroup of both entry points
WORKGROUP = 64

LAYOUT = """\
// Skinning in two compute passes over flat f32 storage buffers (one bind group, group 0):
//   {p}_skin_bones : affines[b] = {p}_versor_to_affine(versors[b]) for b < n_bones
//   {p}_skin_blend : skinned[i] = {p}_affine_point(sum_k weights[i,k] affines[joints[i,k]], rest[i])
// Buffers (row-major, no padding):
//   binding 0  uniform {p}SkinParams {{n_bones, n_vertices, n_influences, pad}} (u32 x 4)
//   binding 1  versors  (n_bones, 12) f32, blade order of the kernels     (read)   bones pass
//   binding 2  affines  (n_bones, 12) f32, row-major 3x4 maps             (write in bones, read in blend)
//   binding 3  rest     (n_vertices, 3) f32                               (read)   blend pass
//   binding 4  joints   (n_vertices, n_influences) u32 bone indices      (read)   blend pass
//   binding 5  weights  (n_vertices, n_influences) f32                    (read)   blend pass
//   binding 6  skinned  (n_vertices, 3) f32                               (write)  blend pass
//   binding 7  bad      3 x atomic u32: influences with a joint index >= n_bones (skipped),
//              negative or NaN weights (used as given), vertices with a non-finite result
//              (zero it before the blend pass; like generated/skinning.py's returned counts)
// Dispatch ceil(count / {wg}) workgroups; above 65535 workgroups use a 2D dispatch (x, y): the
// index is global_invocation_id.x + global_invocation_id.y * num_workgroups.x * {wg}.
// A blend may also take affines computed elsewhere (e.g. on the CPU): the bones pass is optional.
"""


def skin_shader(prefix: str, kernels_source: str) -> str:
    """The skinning shader text: the layout comment, the bindings, ``kernels_source`` (the WGSL
    functions ``<prefix>_versor_to_affine`` and ``<prefix>_affine_point`` and their helpers) and the
    two entry points ``<prefix>_skin_bones``, ``<prefix>_skin_blend``."""
    p, wg = prefix, WORKGROUP
    bindings = f"""\
struct {p}SkinParams {{
    n_bones: u32,
    n_vertices: u32,
    n_influences: u32,
    pad: u32,
}}

@group(0) @binding(0) var<uniform> {p}_params: {p}SkinParams;
@group(0) @binding(1) var<storage, read> {p}_versors: array<f32>;
@group(0) @binding(2) var<storage, read_write> {p}_affines: array<f32>;
@group(0) @binding(3) var<storage, read> {p}_rest: array<f32>;
@group(0) @binding(4) var<storage, read> {p}_joints: array<u32>;
@group(0) @binding(5) var<storage, read> {p}_weights: array<f32>;
@group(0) @binding(6) var<storage, read_write> {p}_skinned: array<f32>;
@group(0) @binding(7) var<storage, read_write> {p}_bad: array<atomic<u32>, 3>;

// WGSL lets an implementation assume floats are finite (lavapipe folds x * 0.0 == 0.0 to true), so
// NaN and infinities are recognised from their bits.
fn {p}_is_nan(x: f32) -> bool {{
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}}

fn {p}_is_finite(x: f32) -> bool {{
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}}
"""
    load_versor = ", ".join(f"{p}_versors[v + {j}u]" for j in range(12))
    store_affine = "\n".join(f"    {p}_affines[v + {j}u] = a[{j}];" for j in range(12))
    accumulate = "\n".join(f"        a[{j}] = a[{j}] + w * {p}_affines[row + {j}u];" for j in range(12))
    entries = f"""\
@compute @workgroup_size({wg})
fn {p}_skin_bones(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let b = gid.x + gid.y * groups.x * {wg}u;
    if (b >= {p}_params.n_bones) {{
        return;
    }}
    let v = b * 12u;
    let a = {p}_versor_to_affine(array<f32, 12>({load_versor}));
{store_affine}
}}

@compute @workgroup_size({wg})
fn {p}_skin_blend(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    let i = gid.x + gid.y * groups.x * {wg}u;
    let n_bones = {p}_params.n_bones;
    let n_influences = {p}_params.n_influences;
    if (i >= {p}_params.n_vertices) {{
        return;
    }}
    var a = array<f32, 12>();
    for (var k = 0u; k < n_influences; k = k + 1u) {{
        let slot = i * n_influences + k;
        let w = {p}_weights[slot];
        if (w < 0.0f || {p}_is_nan(w)) {{
            atomicAdd(&{p}_bad[1], 1u);
        }}
        let b = {p}_joints[slot];
        // the index is checked before it is read; a bad one is skipped (u32: a negative index
        // written as i32 reads as >= 2^31, also skipped)
        if (b >= n_bones) {{
            atomicAdd(&{p}_bad[0], 1u);
            continue;
        }}
        let row = b * 12u;
{accumulate}
    }}
    let x = {p}_affine_point(a, array<f32, 3>({p}_rest[3u * i], {p}_rest[3u * i + 1u], {p}_rest[3u * i + 2u]));
    {p}_skinned[3u * i] = x[0];
    {p}_skinned[3u * i + 1u] = x[1];
    {p}_skinned[3u * i + 2u] = x[2];
    if (!({p}_is_finite(x[0]) && {p}_is_finite(x[1]) && {p}_is_finite(x[2]))) {{
        atomicAdd(&{p}_bad[2], 1u);
    }}
}}
"""
    return LAYOUT.format(p=p, wg=wg) + "\n" + bindings + "\n" + kernels_source + "\n" + entries
