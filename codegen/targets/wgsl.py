"""WGSL (WebGPU) printer of the kernel IR: every kernel as an f32 WGSL function, and the skinning
compute shader (per-bone ``versor_to_affine``, per-vertex blend).

Conventions of the written files (``<prefix>.wgsl``, ``<prefix>_f64.wgsl``, ``<prefix>_skin.wgsl``):

- Kernel ``k`` is ``fn <prefix>_k(<input>: array<f32, size>, <scalar>: f32, ...) -> array<f32, N>``:
  multivector inputs in the blade order of generated/layout.py, arrays flat (a 3x4 matrix row-major
  as 12), N the number of outputs (1 for a scalar result: take ``[0]``). Every value is f32.
- WGSL has no conditional expression: a Piecewise prints as ``select(false_value, true_value, cond)``.
  Both values are computed and one is picked, so a division by zero in the untaken branch only makes
  a value that is thrown away.
- WGSL has no ``cbrt``: ``<prefix>_cbrt`` (exp2/log2 plus one Newton step: within about 1 ulp of
  f32 in the tests; subnormal inputs as the implementation treats them), and no NaN literal:
  ``<prefix>_nan()`` bitcasts a private variable (a constant expression that evaluates to NaN is a
  shader-creation error in WGSL). Only a Piecewise without a final ``True`` branch reaches it (the
  numba side's ``math.nan``). WGSL lets an implementation assume values are finite, so NaN/inf
  results are not guaranteed to propagate as in numba (on lavapipe they do in the tests).
- Literals are f32 (suffix ``f``). A literal outside f32's range keeps its intent: a magnitude above
  the largest f32 prints as ±3.4028235e38f, a nonzero magnitude below the smallest normal f32 as
  ±1.1754944e-38f (GPUs may flush subnormals to zero, which would turn ``x > 1e-300`` into
  ``x > 0``); the kernel's comment lists every such replacement.
- Names that WGSL reserves (``filter``, ``target``, ``move``, ...) or that would shadow a builtin the
  kernels call (``sin``, ``select``, ...) get a trailing ``_``.
- ``<prefix>_f64.wgsl``: the same functions (same names, include one file or the other) in f64 for
  wgpu-native's ``shader-f64`` feature (WebGPU itself has no f64), literals suffixed ``lf``, for the
  kernels that need no function but sqrt, abs, sign, max, min (``F64_FUNCTIONS``): SPIR-V's
  GLSL.std.450 defines sin, cos, exp, log, atan2, acos, the hyperbolic functions (and the exp2/log2
  of the cbrt helper) for 16- and 32-bit floats only, and on lavapipe they silently return garbage
  on f64. The file's leading comment lists the kernels left out.

The skinning file is self-contained (WGSL has no #include): it repeats the two kernels it calls.
"""
from __future__ import annotations


import numpy as np
import sympy

from ..expressions import Dialect, kernel_body
from ..ir import renamed
from .wgsl_names import safe_name
from .wgsl_skin import skin_shader

#: f32 limits for literals (see the module docstring)
F32_MAX = float(np.finfo(np.float32).max)
F32_TINY = float(np.finfo(np.float32).tiny)

FUNCTIONS = {
    sympy.sin: "sin({})", sympy.cos: "cos({})", sympy.atan2: "atan2({}, {})", sympy.acos: "acos({})",
    sympy.log: "log({})", sympy.exp: "exp({})", sympy.Abs: "abs({})", sympy.sign: "sign({})",
    sympy.atanh: "atanh({})", sympy.cosh: "cosh({})", sympy.sinh: "sinh({})",
    sympy.Max: "max({}, {})", sympy.Min: "min({}, {})"}


def f32_literal(value, replaced: list | None = None) -> str:
    """``value`` as a WGSL f32 literal (shortest text that reads back as the same f32); a value
    outside f32's normal range is replaced (see the module docstring) and noted in ``replaced``."""
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"no WGSL literal for {v}")
    mag = abs(v)
    if mag > F32_MAX or 0.0 < mag < F32_TINY:
        kept = F32_MAX if mag > F32_MAX else F32_TINY
        text = _shortest(np.float32(np.copysign(kept, v)))
        if replaced is not None:
            replaced.append(f"{v!r} -> {text}f")
    else:
        text = _shortest(np.float32(v))
    return text + "f"


def _shortest(x: np.float32) -> str:
    """The shortest decimal that reads back as ``x`` (numpy's f32 repr), in a form WGSL accepts."""
    text = np.format_float_positional(x, unique=True, trim="0")
    sci = np.format_float_scientific(x, unique=True, trim="0")
    text = sci if len(sci) < len(text) else text
    return text if any(c in text for c in ".e") else text + ".0"


def f64_literal(value) -> str:
    """``value`` as a WGSL f64 literal (``lf``: naga's f64 suffix)."""
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"no WGSL literal for {v}")
    text = repr(v)
    return (text if any(c in text for c in ".e") else text + ".0") + "lf"


#: the functions a kernel may call to have an f64 variant (see the module docstring)
F64_FUNCTIONS = frozenset({sympy.Abs, sympy.sign, sympy.Max, sympy.Min, sympy.Piecewise})


def f64_ready(kernel) -> bool:
    """Whether ``kernel`` calls nothing but ``F64_FUNCTIONS`` and sqrt (no cbrt, no transcendental)."""
    exprs = [e for _, e in kernel.lets] + list(kernel.outputs)
    for e in exprs:
        if any(type(f) not in F64_FUNCTIONS for f in e.atoms(sympy.Function)):
            return False
        if any(p.exp.is_Rational and p.exp.q == 3 for p in e.atoms(sympy.Pow)):
            return False
    return True


def dialect(prefix: str, replaced: list, real: str = "f32") -> Dialect:
    """The WGSL dialect for kernels named ``<prefix>_*`` in ``real`` (f32 or f64); replaced f32
    literals are appended to ``replaced``."""
    return Dialect(
        "wgsl" if real == "f32" else "wgsl-f64", FUNCTIONS,
        literal=(lambda v: f32_literal(v, replaced)) if real == "f32" else f64_literal,
        select=lambda cond, a, b: f"select({b}, {a}, {cond})",
        conjunction=(" && ", " || "), true="true",
        nan=f"{prefix}_nan()" if real == "f32" else f"f64({prefix}_nan())",
        sqrt="sqrt({})", cbrt=f"{prefix}_cbrt({{}})")


def helpers(prefix: str) -> dict[str, str]:
    """{name: WGSL source} of the helper functions kernels may call."""
    return {
        f"{prefix}_cbrt": f"""\
// Real cube root (WGSL has none): exp2(log2|x| / 3), then one Newton step y -= (y - |x| / y^2) / 3,
// which takes the result to within about 1 ulp (tested); 0 and infinities pass through; subnormal
// inputs follow the implementation (WGSL may flush them to zero).
fn {prefix}_cbrt(x: f32) -> f32 {{
    let ax = abs(x);
    let y0 = exp2(log2(ax) * (1.0f / 3.0f));
    let y = y0 - (y0 - ax / (y0 * y0)) * (1.0f / 3.0f);
    return sign(x) * select(y, ax, ax == 0.0f || ax > {_shortest(np.float32(F32_MAX))}f);
}}
""",
        f"{prefix}_nan": f"""\
// A quiet NaN (WGSL has no NaN literal, and a constant expression that evaluates to NaN is an error,
// so the bits come from a private variable).
var<private> {prefix}_nan_bits: u32 = 0x7fc00000u;
fn {prefix}_nan() -> f32 {{
    return bitcast<f32>({prefix}_nan_bits);
}}
"""}


def safe_kernel(kernel):
    """``kernel`` with every input and symbol name that WGSL would not accept renamed."""
    return renamed(kernel, safe_name)


def param_type(inp, real: str = "f32") -> str:
    return real if inp.kind == "scalar" else f"array<{real}, {len(inp.symbols)}>"


def kernel_function(kernel, prefix: str, uniform=(), real: str = "f32") -> str:
    """WGSL source of ``fn <prefix>_<name>(...) -> array<real, N>`` with a leading comment."""
    original = kernel
    kernel = safe_kernel(kernel)
    replaced: list = []
    assigns, values = kernel_body(kernel, dialect(prefix, replaced, real))
    lines = [f"// {line}".rstrip() for line in original.doc.strip().splitlines()]
    for inp, orig in zip(kernel.inputs, original.inputs):
        role = " (uniform: the same for every row of a batch)" if orig.name in uniform else ""
        layout = "" if inp.kind != "multivector" else " = (" + ", ".join(map(str, inp.labels)) + ")"
        lines.append(f"//   {inp.name}: {param_type(inp, real)}{layout}{role}")
    lines.append(f"//   returns array<{real}, {len(values)}> = ({', '.join(original.output_labels)})"
                 + (f", shape {original.output_shape} row-major" if len(original.output_shape) > 1 else ""))
    lines += [f"//   f32 literal out of range: {r}" for r in dict.fromkeys(replaced)]
    params = ", ".join(f"{i.name}: {param_type(i, real)}" for i in kernel.inputs)
    lines.append(f"fn {prefix}_{kernel.name}({params}) -> array<{real}, {len(values)}> {{")
    for inp in kernel.inputs:
        if inp.kind != "scalar":
            lines += [f"    let {s.name} = {inp.name}[{j}];" for j, s in enumerate(inp.symbols)]
    lines += [f"    let {name} = {code};" for name, code, _ in assigns]
    lines.append(f"    return array<{real}, {len(values)}>(")
    lines += [f"        {v}," for v in values]
    lines.append("    );")
    lines.append("}")
    return "\n".join(lines) + "\n"


def comment(header) -> str:
    return "".join(f"// {line}".rstrip() + "\n" for line in header)


def library(functions: list[str], prefix: str) -> str:
    """The helper functions that ``functions`` (WGSL sources) call, then the functions."""
    used = [src for name, src in helpers(prefix).items() if any(f"{name}(" in f for f in functions)]
    return "\n".join(used + functions)


def render(kernels, *, prefix, header, uniform=None, skinning=False) -> dict[str, str]:
    """{``<prefix>.wgsl``: every kernel as an f32 function, ``<prefix>_f64.wgsl``: the kernels
    that f64 can run (``f64_ready``) as f64 functions, ``<prefix>_skin.wgsl`` (with ``skinning``):
    the skinning compute shader}. See the module docstring for the conventions."""
    uniform = uniform or {}
    functions = [kernel_function(k, prefix, uniform.get(k.name, ())) for k in kernels]
    intro = (f"// Kernels as WGSL functions (f32): fn {prefix}_<kernel>(inputs) -> array<f32, N>.\n"
             "// Inputs are flat arrays (multivectors in the blade order listed per kernel) or f32 scalars.\n")
    files = {f"{prefix}.wgsl": comment(header) + intro + "\n" + library(functions, prefix)}
    ready = [k for k in kernels if f64_ready(k)]
    if ready:
        left_out = [k.name for k in kernels if not f64_ready(k)]
        intro = (f"// The kernels in f64, for wgpu-native's shader-f64 feature (WebGPU has no f64): the same\n"
                 f"// functions as {prefix}.wgsl (include one file or the other), f64 values and inputs.\n"
                 "// Only kernels that need no function but sqrt, abs, sign, max, min: SPIR-V defines the\n"
                 "// transcendental functions for 16/32-bit floats only.\n"
                 + (f"// Left out (f32 only): {', '.join(left_out)}\n" if left_out else ""))
        functions = [kernel_function(k, prefix, uniform.get(k.name, ()), "f64") for k in ready]
        files[f"{prefix}_f64.wgsl"] = comment(header) + intro + "\n" + library(functions, prefix)
    if skinning:
        by_name = {k.name: k for k in kernels}
        missing = [n for n in ("versor_to_affine", "affine_point") if n not in by_name]
        if missing:
            raise ValueError(f"skinning needs the kernels {missing}")
        used = [kernel_function(by_name[n], prefix) for n in ("versor_to_affine", "affine_point")]
        files[f"{prefix}_skin.wgsl"] = comment(header) + skin_shader(prefix, library(used, prefix))
    return files
