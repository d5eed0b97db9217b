"""JavaScript printer of the kernel IR: every kernel as a function of an ES module, in double precision.

JavaScript numbers are IEEE float64 and ``Math`` has every function the kernels call (sqrt, cbrt, sin,
cos, exp, log, atan2, acos, atanh, sinh, cosh), so the printed kernels compute what the numba kernels
compute, to rounding: a page (three.js, WebGL) composes the bones' versors with them each frame
before a shader blends them in float (``glsl_skin.webgl_chunk``).

Files (``render``): ``<prefix>.mjs``. Kernel ``k`` with inputs ``a`` (12 coefficients), ``x`` (3) and
scalar ``s`` and N outputs is

    export function <prefix>_k(a, x, s, out = new Float64Array(N))   // returns out

in the numba kernels' layouts (flat arrays in the blade order of generated/layout.py, a 3x4 matrix
row-major as 12); array inputs are anything indexable (Array, Float64Array, Float32Array); ``out``
may be a caller's array to write into (no allocation per call). Local names that JavaScript reserves
(``in``, ``new``, ``this``, ...) or that the printed function itself uses (``out``) get a ``v_``
prefix. Where the numba kernel takes ``max``/``min`` with a NaN, ``Math.max``/``Math.min`` return
NaN (no built-in kernel uses them).
"""
from __future__ import annotations

import math
import re

import sympy

from ..expressions import Dialect, kernel_body
from ..ir import Kernel, renamed

#: JavaScript's reserved words (ES2023, strict mode), globals a name must not shadow, and ``out``
RESERVED = frozenset("""
await break case catch class const continue debugger default delete do else enum export extends false
finally for function if implements import in instanceof interface let new null package private protected
public return static super switch this throw true try typeof var void while with yield arguments eval
Math NaN Infinity undefined out Float64Array Array Object
""".split())


def js_literal(value) -> str:
    v = float(value)
    if v != v:
        return "NaN"
    if math.isinf(v):
        return "Infinity" if v > 0 else "(-Infinity)"
    return repr(v)


JS = Dialect(
    "js",
    {sympy.sin: "Math.sin({})", sympy.cos: "Math.cos({})", sympy.atan2: "Math.atan2({}, {})",
     sympy.acos: "Math.acos({})", sympy.log: "Math.log({})", sympy.exp: "Math.exp({})",
     sympy.Abs: "Math.abs({})", sympy.sign: "Math.sign({})", sympy.atanh: "Math.atanh({})",
     sympy.cosh: "Math.cosh({})", sympy.sinh: "Math.sinh({})", sympy.Max: "Math.max({})",
     sympy.Min: "Math.min({})"},
    literal=js_literal,
    select=lambda cond, a, b: f"({cond} ? {a} : {b})",
    conjunction=(" && ", " || "),
    true="true",
    nan="NaN",
    sqrt="Math.sqrt({})",
    cbrt="Math.cbrt({})",
)


def _js_name(name: str) -> str:
    """A legal, unreserved JavaScript identifier for a kernel's local name (unchanged when it is one)."""
    safe = re.sub(r"[^A-Za-z0-9_$]", lambda m: f"u{ord(m.group()):x}", name)
    if safe in RESERVED or safe[0].isdigit() or safe != name:
        safe = f"v_{safe}"
    return safe


def kernel_function(kernel: Kernel, prefix: str, uniform=()) -> str:
    """``export function <prefix>_<name>(inputs..., out = new Float64Array(N))`` with the kernel's body."""
    kernel = renamed(kernel, _js_name)
    n_out = len(kernel.outputs)
    lines = ["/**"] + [f" * {line}" if line else " *" for line in kernel.doc.strip().splitlines()]
    for i in kernel.inputs:
        what = "scalar" if i.kind == "scalar" else f"({len(i.symbols)},) " + " ".join(str(x) for x in i.labels)
        once = "; the same for every row in the batch form" if i.name in uniform else ""
        lines.append(f" *   {i.name}: {what}{once}")
    lines.append(f" *   returns out: {kernel.output_shape} flattened row-major to ({n_out},): "
                 + " ".join(kernel.output_labels))
    lines.append(" */")
    params = [i.name for i in kernel.inputs] + [f"out = new Float64Array({n_out})"]
    lines.append(f"export function {prefix}_{kernel.name}({', '.join(params)}) {{")
    for i in kernel.inputs:
        if i.kind != "scalar":
            lines += [f"    const {s.name} = {i.name}[{n}];" for n, s in enumerate(i.symbols)]
    assigns, values = kernel_body(kernel, JS)
    lines += [f"    const {name} = {code};" for name, code, _ in assigns]
    lines += [f"    out[{n}] = {v};" for n, v in enumerate(values)]
    lines += ["    return out;", "}"]
    return "\n".join(lines) + "\n"


def render(kernels, *, prefix: str, header, uniform=None, skinning: bool = False) -> dict[str, str]:
    """{``<prefix>.mjs``: every kernel as an exported function} (the contract of ``codegen.targets``;
    the skinning blend of a page runs in its vertex shader: ``glsl_skin.webgl_chunk``)."""
    notes = ["", "An ES module: import { <prefix>_<kernel> } from './<prefix>.mjs'. Double precision",
             "(JavaScript numbers are float64): the numba kernels' results to rounding. Flat arrays in the",
             "numba kernels' layouts (blade order of generated/layout.py); a 3x4 matrix is 12 numbers",
             "row-major. The last argument, out, is optional: pass an array to write into it."]
    top = "\n".join(["// cgaskin kernels for JavaScript (ES2015 modules), double precision"]
                    + [f"// {line}" if line else "//" for line in list(header) + notes]) + "\n"
    parts = [top] + [kernel_function(k, prefix, (uniform or {}).get(k.name, ())) for k in kernels]
    return {f"{prefix}.mjs": "\n".join(parts)}
