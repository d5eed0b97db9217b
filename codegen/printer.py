"""Print a ``Kernel`` as a numba module function (straight-line code, no closures).

Rules: float literals everywhere, no ``**`` (integer powers become products, negative powers
divisions, half powers ``sqrt``), every division parenthesised, sums printed as balanced trees
(shorter dependency chains and error growth ~log n instead of ~n), Piecewise as a conditional
expression. CSE runs here, per group (each ``let``, then all outputs), so temporaries never refer to
a let that is not yet computed.
"""
from __future__ import annotations

import sympy
from sympy import Add, Mul, Pow, Piecewise, Rational, Symbol

from .ir import CodegenError, Kernel

FUNCTIONS = {sympy.sin: "math.sin", sympy.cos: "math.cos", sympy.atan2: "math.atan2",
             sympy.acos: "math.acos", sympy.log: "math.log", sympy.exp: "math.exp",
             sympy.Abs: "abs", sympy.sign: "np.sign", sympy.atanh: "math.atanh",
             sympy.cosh: "math.cosh", sympy.sinh: "math.sinh"}


def literal(value) -> str:
    return repr(float(value))


def _balanced(parts: list[str], op: str) -> str:
    if len(parts) == 1:
        return parts[0]
    mid = len(parts) // 2
    return f"({_balanced(parts[:mid], op)} {op} {_balanced(parts[mid:], op)})"


def expr_code(e) -> str:
    if isinstance(e, Symbol):
        return e.name
    if e.is_Number:
        return literal(e) if not e.is_negative else f"({literal(e)})"
    if e is sympy.true:
        return "True"
    if isinstance(e, Add):
        terms = list(e.args)
        positives = [expr_code(t) for t in terms if not t.could_extract_minus_sign()]
        negatives = [expr_code(-t) for t in terms if t.could_extract_minus_sign()]
        if not positives:
            return f"(-{_balanced(negatives, '+')})"
        if not negatives:
            return _balanced(positives, "+")
        return f"({_balanced(positives, '+')} - {_balanced(negatives, '+')})"
    if isinstance(e, Mul):
        coeff, rest = e.as_coeff_Mul()
        if coeff == -1:
            return f"(-{expr_code(rest)})"
        num, den = [], []
        for f in Mul.make_args(e):
            if isinstance(f, Pow) and f.exp.is_Number and f.exp < 0:
                den.append(expr_code(Pow(f.base, -f.exp)))
            elif isinstance(f, Rational) and not f.is_Integer and f.p in (1, -1):
                # 1/2 prints as a multiplication by 0.5, not a division
                num.append(literal(f))
            else:
                num.append(expr_code(f))
        text = _balanced(num, "*") if num else "1.0"
        return f"({text} / {_balanced(den, '*')})" if den else text
    if isinstance(e, Pow):
        base, exp = e.base, e.exp
        if exp == Rational(1, 2):
            return f"math.sqrt({expr_code(base)})"
        if exp == Rational(1, 3):
            return f"np.cbrt({expr_code(base)})"
        if exp == Rational(-1, 2):
            return f"(1.0 / math.sqrt({expr_code(base)}))"
        if exp.is_Integer and exp > 0:
            b = expr_code(base)
            return "(" + " * ".join([b] * int(exp)) + ")"
        if exp.is_Integer and exp < 0:
            return f"(1.0 / {expr_code(Pow(base, -exp))})"
        raise CodegenError(f"cannot print power {e}")
    if isinstance(e, (sympy.core.relational.Relational, sympy.And, sympy.Or)):
        return cond_code(e)                        # a condition CSE took out of a Piecewise
    if isinstance(e, Piecewise):
        (val, cond), *rest = e.args
        if cond is sympy.true:
            return expr_code(val)
        other = expr_code(Piecewise(*rest)) if rest else "math.nan"
        return f"({expr_code(val)} if {cond_code(cond)} else {other})"
    if e.func in FUNCTIONS:
        return f"{FUNCTIONS[e.func]}({', '.join(expr_code(a) for a in e.args)})"
    if isinstance(e, (sympy.Max, sympy.Min)):
        name = "max" if isinstance(e, sympy.Max) else "min"
        return f"{name}({', '.join(expr_code(a) for a in e.args)})"
    raise CodegenError(f"cannot print {type(e).__name__}: {e}")


def cond_code(c) -> str:
    ops = {sympy.StrictLessThan: "<", sympy.LessThan: "<=", sympy.StrictGreaterThan: ">",
           sympy.GreaterThan: ">="}
    for cls, op in ops.items():
        if isinstance(c, cls):
            return f"({expr_code(c.lhs)} {op} {expr_code(c.rhs)})"
    if isinstance(c, Symbol):                       # a condition that CSE named
        return c.name
    if isinstance(c, sympy.And):
        return "(" + " and ".join(cond_code(a) for a in c.args) + ")"
    if isinstance(c, sympy.Or):
        return "(" + " or ".join(cond_code(a) for a in c.args) + ")"
    raise CodegenError(f"cannot print condition {c}")


def _cse_lines(exprs, prefix):
    replacements, reduced = sympy.cse(list(exprs), symbols=sympy.numbered_symbols(prefix),
                                      order="none")
    lines = [f"    {s} = {expr_code(e)}" for s, e in replacements]
    return lines, [expr_code(e) for e in reduced]


def docstring(kernel: Kernel, width: int = 110) -> list[str]:
    lines = ['    """' + kernel.doc.strip()]
    lines.append("")
    lines.append("    Symbolic expansion (before CSE):")
    for row in kernel.expansion:
        text = row if len(row) <= width else row[: width - 5] + " ..."
        lines.append("        " + text.replace("\\", "\\\\"))
    lines.append('    """')
    return lines


def print_kernel(kernel: Kernel) -> str:
    """Source of ``@njit def name(inputs...) -> tuple`` (the scalar kernel)."""
    args = ", ".join(i.name for i in kernel.inputs)
    lines = [f"@njit(cache=True, error_model='numpy', nogil=True)", f"def {kernel.name}({args}):"]
    lines += docstring(kernel)
    for inp in kernel.inputs:
        if inp.kind == "scalar":
            continue
        for idx, sym in enumerate(inp.symbols):
            lines.append(f"    {sym.name} = {inp.name}[{idx}]")
    for n, (sym, expr) in enumerate(kernel.lets):
        body, (value,) = _cse_lines([expr], f"l{n}_")
        lines += body
        lines.append(f"    {sym.name} = {value}")
    body, values = _cse_lines(kernel.outputs, "t")
    lines += body
    if len(values) == 1:
        lines.append(f"    return {values[0]}")
    else:
        lines.append("    return (")
        lines += [f"        {v}," for v in values]
        lines.append("    )")
    return "\n".join(lines) + "\n"


def print_batch(kernel: Kernel) -> str:
    """Source of ``name_batch(inputs (N, ...)..., out (N, k))``: the scalar kernel over rows."""
    args = [i.name for i in kernel.inputs]
    if "row" in args:
        raise CodegenError(f"{kernel.name}: an input named 'row' would shadow the batch loop index")
    n_out = len(kernel.outputs)
    lines = [f"@njit(cache=True, error_model='numpy', nogil=True)",
             f"def {kernel.name}_batch({', '.join(args)}, out):",
             f'    """``{kernel.name}`` on every row: inputs (N, ...) or (N,), out (N, {n_out})."""',
             f"    for row in range(out.shape[0]):"]
    call = f"{kernel.name}({', '.join(a + '[row]' for a in args)})"
    if n_out == 1:
        lines.append(f"        out[row, 0] = {call}")
    else:
        lines.append(f"        r = {call}")
        lines += [f"        out[row, {j}] = r[{j}]" for j in range(n_out)]
    return "\n".join(lines) + "\n"
