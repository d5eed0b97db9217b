"""GLSL printer of the kernel IR: includes of functions for #version 430/450 shaders (``glsl.render``
writes them, and the skinning shaders of ``glsl_skin``).

Files (``render``):

<prefix>.glsl      every kernel as a double-precision function (doubles are core GLSL since 4.00, the
                   ``GL_ARB_gpu_shader_fp64`` features; literals suffixed ``lf``), with the double
                   scalar functions of ``glsl_math`` (GLSL has no double exp/sin/log/atan/...)
<prefix>_f32.glsl  the same functions in float, for drivers without fp64 (GLSL's float exp, sin, cos,
                   cosh; ``glsl_math``'s float log, atan2, acos, atanh, sinh, cbrt)

Neither has a #version line: paste or ``#include`` it after your own. Both can be included together:
the two precisions are overloads of the same names (GLSL picks by the argument types). A kernel ``k``
with inputs ``a`` (12 coefficients), ``x`` (3) and scalar ``s`` and 3 outputs becomes

    void <prefix>_k(in double a[12], in double x[3], in double s, out double result[3]);
    void <prefix>_k(in float a[12], in float x[3], in float s, out float result[3]);    // _f32.glsl

in the layouts of the numba kernels (flat arrays in the blade order of generated/layout.py; a 3x4
output row-major as 12). Helpers are ``<prefix>_lib_*`` (so no kernel name may start with ``lib_``).
``uniform`` only documents which inputs the batch form takes once: in GLSL the calling shader decides
where an input comes from.
"""
from __future__ import annotations

import re

import sympy

from ..expressions import Dialect, kernel_body
from ..ir import CodegenError, Kernel, renamed
from .glsl_math import DOUBLE_FUNCTIONS, FLOAT_FUNCTIONS, library

#: GLSL keywords, reserved words and the built-in functions a kernel's local names must not shadow
RESERVED = frozenset("""
attribute const uniform varying buffer shared coherent volatile restrict readonly writeonly atomic_uint
layout centroid flat smooth noperspective patch sample break continue do for while switch case default
if else subroutine in out inout float double int void bool true false invariant precise discard return
lowp mediump highp precision struct common partition active asm class union enum typedef template this
resource goto inline noinline public static extern external interface long short half fixed unsigned
superp input output filter sizeof cast namespace using row_major packed
vec2 vec3 vec4 dvec2 dvec3 dvec4 ivec2 ivec3 ivec4 uvec2 uvec3 uvec4 bvec2 bvec3 bvec4 mat2 mat3 mat4
dmat2 dmat3 dmat4 uint
radians degrees sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh pow exp log exp2 log2 sqrt
inversesqrt abs sign floor trunc round roundEven ceil fract mod modf min max clamp mix step smoothstep
isnan isinf fma frexp ldexp length distance dot cross normalize reflect refract result
""".split())


def _glsl_name(name: str) -> str:
    """A legal, unreserved GLSL identifier for a kernel's local name (unchanged when it is one)."""
    safe = re.sub(r"[^A-Za-z0-9_]", lambda m: f"u{ord(m.group()):x}", name)
    safe = re.sub(r"_{2,}", "_", safe)
    if safe in RESERVED or safe.startswith("gl_") or safe[0].isdigit() or safe != name:
        safe = f"v_{safe}"
    return safe


def glsl_kernel(kernel: Kernel) -> Kernel:
    """``kernel`` with every input, input symbol and let renamed to a legal GLSL identifier (the
    built-in and README catalogues need none; a user's ``sample`` or ``input`` would)."""
    return renamed(kernel, _glsl_name)


def dialect(prefix: str, double: bool) -> Dialect:
    """GLSL in double (``lf`` literals, the ``<prefix>_lib_*`` functions) or in float (built-ins)."""
    if double:
        functions = {getattr(sympy, n): f"{prefix}_lib_{n}({{}}" + (", {})" if n == "atan2" else ")")
                     for n in DOUBLE_FUNCTIONS}
        literal = lambda v: repr(float(v)) + "lf"                          # noqa: E731
    else:
        functions = {sympy.exp: "exp({})", sympy.sin: "sin({})", sympy.cos: "cos({})", sympy.cosh: "cosh({})"}
        functions.update({getattr(sympy, n): f"{prefix}_lib_{n}({{}}" + (", {})" if n == "atan2" else ")")
                          for n in FLOAT_FUNCTIONS})
        literal = lambda v: repr(float(v))                                 # noqa: E731 (unsuffixed: float)
    functions.update({sympy.Abs: "abs({})", sympy.sign: "sign({})", sympy.Max: "max({}, {})",
                      sympy.Min: "min({}, {})"})
    return Dialect("glsl" if double else "glsl-f32", functions, literal=literal,
                   select=lambda cond, a, b: f"({cond} ? {a} : {b})", conjunction=(" && ", " || "),
                   true="true", nan=f"{prefix}_lib_nan{'' if double else 'f'}()", sqrt="sqrt({})", cbrt=f"{prefix}_lib_cbrt({{}})")


def kernel_function(kernel: Kernel, prefix: str, d: Dialect, real: str, uniform=()) -> str:
    """``void <prefix>_<name>(in <real> input[n]..., out <real> result[k])`` with the kernel's body."""
    kernel = glsl_kernel(kernel)
    params = [f"in {real} {i.name}" if i.kind == "scalar" else f"in {real} {i.name}[{len(i.symbols)}]"
              for i in kernel.inputs]
    n_out = len(kernel.outputs)
    lines = [f"// {line}" for line in kernel.doc.strip().splitlines()]
    for i in kernel.inputs:
        what = "scalar" if i.kind == "scalar" else f"({len(i.symbols)},) " + " ".join(str(x) for x in i.labels)
        once = "; the same for every row in the batch form" if i.name in uniform else ""
        lines.append(f"//   {i.name}: {what}{once}")
    lines.append(f"//   result: {kernel.output_shape} flattened row-major to ({n_out},): "
                 + " ".join(kernel.output_labels))
    lines.append(f"void {prefix}_{kernel.name}({', '.join(params + [f'out {real} result[{n_out}]'])}) {{")
    for i in kernel.inputs:
        if i.kind != "scalar":
            lines += [f"    {real} {s.name} = {i.name}[{n}];" for n, s in enumerate(i.symbols)]
    assigns, values = kernel_body(kernel, d)
    lines += [f"    {'bool' if cond else real} {name} = {code};" for name, code, cond in assigns]
    lines += [f"    result[{n}] = {v};" for n, v in enumerate(values)]
    lines.append("}")
    return "\n".join(lines) + "\n"


def comment(header, title: str) -> str:
    return "\n".join(["// " + title] + [f"// {line}" if line else "//" for line in header]) + "\n"


def include(kernels, prefix: str, header, double: bool, uniform=None) -> str:
    """The text of ``<prefix>.glsl`` (double) or ``<prefix>_f32.glsl`` (float)."""
    for k in kernels:
        if k.name.startswith("lib_"):
            raise CodegenError(f"{k.name}: GLSL kernel names may not start with lib_ (the helpers' prefix)")
    real = "double" if double else "float"
    d = dialect(prefix, double)
    title = (f"cgaskin kernels for GLSL #version 430/450, {real} precision"
             + (" (fp64 is core since GLSL 4.00: GL_ARB_gpu_shader_fp64)" if double else
                " (no fp64 needed; the double overloads are in the .glsl without _f32)"))
    notes = ["", "No #version line: include this after your shader's own. Flat arrays in the numba kernels'",
             "layouts (blade order of generated/layout.py); a 3x4 matrix is 12 floats row-major."]
    if double:
        notes += ["GLSL has no double exp/log/sin/cos/atan/acos/atanh/sinh/cosh/pow/cbrt: the <prefix>_lib_*",
                  "functions below evaluate them in double (a few ulp; sin/cos argument reduction exact for",
                  "|x| < 1.6e6; results below 2^-1022 may flush to zero), so every kernel, versor_log and",
                  "versor_exp included, is double-precision throughout."]
    else:
        notes += ["exp/sin/cos/cosh are GLSL's float built-ins (driver accuracy); log, atan2, acos, atanh,",
                  "sinh and cbrt are the <prefix>_lib_* functions below (GLSL's are inaccurate or absent)."]
    parts = [comment(list(header) + notes, title), library(prefix, double)]
    parts += [kernel_function(k, prefix, d, real, (uniform or {}).get(k.name, ())) for k in kernels]
    return "\n".join(parts)
