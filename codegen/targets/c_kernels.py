"""C99 printer of the kernel IR: headers of ``static inline`` functions (double and float), and skinning headers.

Files (``render``):

``<prefix>.h``
    ``#include <math.h>`` and ``<stddef.h>`` (size_t) only; every function is ``<PREFIX>_API``, which
    defaults to ``static inline`` (define it, e.g. empty, before including the header to get external
    definitions; in a -fPIC library those are interposable and not inlined into the loops, so fast
    code exports wrappers of the static inline functions instead). For each kernel ``k``:

    ``void <prefix>_k(const double a[12], const double x[3], double angle, double out[N])``
        multivector and array inputs as flat arrays in the blade order of generated/layout.py, scalar
        inputs as ``double``, the N outputs (a 3x4 matrix row-major as 12) written to ``out``;
    ``void <prefix>_k_batch(size_t n_rows, const double *a, const double *x, const double *angle,
    double *out)``
        the kernel on every row of row-major inputs (``a`` is n_rows x 12, a scalar input is n_rows
        values, ``out`` n_rows x N); an input the catalogue declares uniform is taken once (a pointer to
        one array, or one ``double``) for every row.

``<prefix>_f32.h``
    the same in float: ``<prefix>_f32_k(const float a[12], ..., float out[N])`` and
    ``<prefix>_f32_k_batch``; every literal is a float literal (``0.5f``) and every libm call the float
    one (``sqrtf``, ``sinf``), so nothing is computed in double (``-Wdouble-promotion`` checks it).
    Both headers can be included together.

``<prefix>_skin.h``, ``<prefix>_skin_f32.h`` (with ``skinning=True``, see ``c_skinning``)
    ``<prefix>_bone_affines`` and ``<prefix>_skin_blend`` (``<prefix>_f32_...`` in float): the two
    stages of generated/skinning.py.

No allocation, no global state; ``-std=c99 -pedantic -Wall -Wextra -Werror`` clean (the tests compile
it so, with -Wshadow -Wconversion -Wdouble-promotion -Wfloat-equal too, and as C++11). Float meets 1e-5
of numba's float64 only where the kernel is well-conditioned at float's input rounding (see
tests/targets/test_c.py); inputs whose products leave float's range (|x| < 2^-10 squared and cubed)
underflow. Where the numba kernel takes ``max``/``min`` of a NaN, C's ``fmax``/``fmin`` return the other
argument (no built-in kernel uses them).
"""
from __future__ import annotations

import math
import re
from dataclasses import replace

import sympy

from ..expressions import Dialect, kernel_body
from ..ir import CodegenError, Kernel

#: names the printed functions use besides the kernel's own inputs
RESERVED = {"out", "n_rows", "row"}
_C_KEYWORDS = set("""auto break case char const continue default do double else enum extern float for goto
if inline int long register restrict return short signed sizeof static struct switch typedef union
unsigned void volatile while""".split())


def c_literal(value) -> str:
    v = float(value)
    if v != v:
        return "NAN"
    if v in (float("inf"), float("-inf")):
        return "INFINITY" if v > 0 else "(-INFINITY)"
    return repr(v)


C99 = Dialect(
    "c99",
    {sympy.sin: "sin({})", sympy.cos: "cos({})", sympy.atan2: "atan2({}, {})", sympy.acos: "acos({})",
     sympy.log: "log({})", sympy.exp: "exp({})", sympy.Abs: "fabs({})", sympy.atanh: "atanh({})",
     sympy.cosh: "cosh({})", sympy.sinh: "sinh({})", sympy.Max: "fmax({}, {})", sympy.Min: "fmin({}, {})"},
    literal=c_literal,
    select=lambda cond, a, b: f"({cond} ? {a} : {b})",
    conjunction=(" && ", " || "),
    true="1",
    nan="NAN",
    sqrt="sqrt({})",
    cbrt="cbrt({})",
)

# float: every literal and libm call in float (a bare 0.5 or sin() would compute in double)
C99_FLOAT = replace(
    C99, name="c99-float",
    functions={f: (t.replace("(", "f(", 1) if not t.startswith("(") else t) for f, t in C99.functions.items()},
    literal=lambda v: c_literal(v) if not math.isfinite(float(v)) else c_literal(v) + "f",
    sqrt="sqrtf({})", cbrt="cbrtf({})")

#: (dialect, C type, name infix) of each precision: ``<prefix>_k`` in double, ``<prefix>_f32_k`` in float
PRECISIONS = {"double": (C99, "double", ""), "float": (C99_FLOAT, "float", "_f32")}

_WORD = re.compile(r"[A-Za-z_]\w*")


def comment(lines, indent: str = "") -> list[str]:
    """A C block comment of ``lines`` (``*/`` inside a line is broken up)."""
    body = [f"{indent} * {line}".rstrip() for line in (l.replace("*/", "* /") for l in lines)]
    return [f"{indent}/*", *body, f"{indent} */"]


def check_names(kernel: Kernel) -> None:
    for inp in kernel.inputs:
        if inp.name in RESERVED or inp.name in _C_KEYWORDS:
            raise CodegenError(f"{kernel.name}: an input named {inp.name!r} collides with a name of the C "
                               f"printer ({sorted(RESERVED)}) or a C keyword")


def parameters(kernel: Kernel, batch: bool = False, uniform=(), real: str = "double") -> list[str]:
    """The C parameters of the scalar function, or of the batch function (row-major pointers)."""
    params = []
    for inp in kernel.inputs:
        if inp.kind == "scalar":
            params.append(f"const {real} *{inp.name}" if batch and inp.name not in uniform
                          else f"{real} {inp.name}")
        else:
            params.append(f"const {real} *{inp.name}" if batch else f"const {real} {inp.name}[{len(inp.symbols)}]")
    params.append(f"{real} *out" if batch else f"{real} out[{len(kernel.outputs)}]")
    return params


def doc_lines(kernel: Kernel) -> list[str]:
    lines = [l for l in kernel.doc.strip().splitlines()]
    for inp in kernel.inputs:
        if inp.kind != "scalar":
            lines.append(f"{inp.name}[{len(inp.symbols)}]: {', '.join(str(l) for l in inp.labels)}")
    lines.append(f"out[{len(kernel.outputs)}]: {', '.join(kernel.output_labels)}")
    return lines


def function_source(kernel: Kernel, name: str, qualifier: str, dialect: Dialect = C99,
                    real: str = "double") -> str:
    """``qualifier void name(inputs..., out)``: the kernel's straight-line body (CSE temporaries as
    ``const`` locals, conditions as ``const int``); only the input components it reads are unpacked,
    unused inputs are cast to void, so ``-Wall -Wextra`` has nothing to say."""
    check_names(kernel)
    assigns, values = kernel_body(kernel, dialect)
    code = [c for _, c, _ in assigns] + values
    used = set()
    for text in code:
        used.update(_WORD.findall(text))
    body = []
    for inp in kernel.inputs:
        if inp.kind == "scalar":
            if inp.symbols[0].name not in used:
                body.append(f"    (void){inp.name};")
            continue
        reads = [(i, s.name) for i, s in enumerate(inp.symbols) if s.name in used]
        if not reads:
            body.append(f"    (void){inp.name};")
        body += [f"    const {real} {sym} = {inp.name}[{i}];" for i, sym in reads]
    for n, (var, text, is_condition) in enumerate(assigns):
        body.append(f"    const {'int' if is_condition else real} {var} = {text};")
        later = [c for c in code[n + 1:]]
        if not any(var in _WORD.findall(c) for c in later):
            body.append(f"    (void){var};")
    body += [f"    out[{j}] = {v};" for j, v in enumerate(values)]
    head = [*comment(doc_lines(kernel)), f"{qualifier} void {name}({', '.join(parameters(kernel, real=real))})"]
    return "\n".join(head + ["{", *body, "}"]) + "\n"


def batch_source(kernel: Kernel, name: str, qualifier: str, uniform=(), loop: str | None = None,
                 real: str = "double") -> str:
    """``name_batch(size_t n_rows, row-major inputs..., out)``: ``name`` on every row. ``loop`` is
    the loop header over ``row`` (a CUDA grid-stride loop for the .cuh); the default is C's."""
    check_names(kernel)
    unknown = set(uniform) - {i.name for i in kernel.inputs}
    if unknown:
        raise CodegenError(f"{kernel.name}: uniform names {sorted(unknown)} are not inputs")
    args = []
    for inp in kernel.inputs:
        if inp.name in uniform:
            args.append(inp.name)
        elif inp.kind == "scalar":
            args.append(f"{inp.name}[row]")
        else:
            args.append(f"{inp.name} + {len(inp.symbols)} * row")
    args.append(f"out + {len(kernel.outputs)} * row")
    loop = loop or "for (row = 0; row < n_rows; ++row)"
    lines = comment([f"{name} on every row: inputs row-major (n_rows x size), out n_rows x {len(kernel.outputs)}"
                     + (f"; uniform (taken once): {', '.join(uniform)}" if uniform else "")])
    lines.append(f"{qualifier} void {name}_batch({', '.join(['size_t n_rows'] + parameters(kernel, True, uniform, real))})")
    lines.append("{")
    if loop.startswith("for (row ="):
        lines.append("    size_t row;")
    lines += [f"    {loop}", f"        {name}({', '.join(args)});", "}"]
    return "\n".join(lines) + "\n"


def guard_name(file_name: str) -> str:
    return re.sub(r"\W", "_", file_name).upper()


def check_prefix(prefix: str) -> None:
    if not re.fullmatch(r"[A-Za-z_]\w*", prefix):
        raise CodegenError(f"prefix {prefix!r} is not a C identifier")


def header_source(kernels, prefix: str, header, uniform=None, precision: str = "double") -> str:
    """The text of ``<prefix>.h`` (double) or ``<prefix>_f32.h`` (float: names ``<prefix>_f32_k``)."""
    check_prefix(prefix)
    dialect, real, infix = PRECISIONS[precision]
    uniform = uniform or {}
    api = f"{prefix.upper()}_API"
    guard = guard_name(f"{prefix}{infix}.h")
    lines = [*comment([*header, "",
                       f"C99 kernels in {real}: {prefix}{infix}_<kernel>(inputs..., out) and "
                       f"{prefix}{infix}_<kernel>_batch(n_rows, ...).",
                       f"Flat {real} arrays in the blade order of cgaskin's generated/layout.py; 3x4 matrices row-major.",
                       f"Every function is {api} (default: static inline); #define {api} (e.g. empty) before",
                       "including this header to get external definitions (one translation unit). In a -fPIC shared",
                       "library those are interposable calls the compiler does not inline into the batch and skinning",
                       "loops (about 2x slower skinning): export your own wrappers of the static inline functions."]),
             f"#ifndef {guard}", f"#define {guard}", "", "#include <math.h>", "#include <stddef.h>", "",
             f"#ifndef {api}", f"#define {api} static inline", "#endif", ""]
    for k in kernels:
        name = f"{prefix}{infix}_{k.name}"
        lines.append(function_source(k, name, api, dialect, real))
        lines.append(batch_source(k, name, api, uniform.get(k.name, ()), real=real))
    lines.append(f"#endif /* {guard} */")
    return "\n".join(lines) + "\n"
