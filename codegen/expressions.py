"""Print sympy expressions as code of one target language (a ``Dialect``): numba's Python, C99,
GLSL, WGSL, CUDA. The kernel IR (``codegen.ir``) is printer-independent; every target prints the same
expressions with the same rules:

float literals everywhere, no ``**`` (integer powers become products, negative powers divisions, half
powers ``sqrt``), every division parenthesised, sums printed as balanced trees (shorter dependency
chains and error growth ~log n instead of ~n), Piecewise as a conditional expression. CSE runs per
group (``cse_assignments``): each ``let``, then all outputs, so temporaries never refer to a let that
is not yet computed.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy
from sympy import Add, Mul, Pow, Piecewise, Rational, Symbol

from .ir import CodegenError


@dataclass(frozen=True)
class Dialect:
    """How one language writes what the kernels use. ``functions`` maps a sympy function to a format
    string whose ``{}`` take the arguments in order (e.g. ``"atan({}, {})"`` for GLSL's atan2)."""

    name: str
    functions: dict
    literal: object = lambda v: repr(float(v))              # float -> text
    select: object = lambda cond, a, b: f"({a} if {cond} else {b})"
    conjunction: tuple = (" and ", " or ")
    true: str = "True"
    nan: str = "math.nan"
    sqrt: str = "math.sqrt({})"
    cbrt: str = "np.cbrt({})"
    relations: dict = field(default_factory=lambda: {sympy.StrictLessThan: "<", sympy.LessThan: "<=",
                                                     sympy.StrictGreaterThan: ">", sympy.GreaterThan: ">="})


PYTHON = Dialect("python", {
    sympy.sin: "math.sin({})", sympy.cos: "math.cos({})", sympy.atan2: "math.atan2({}, {})",
    sympy.acos: "math.acos({})", sympy.log: "math.log({})", sympy.exp: "math.exp({})",
    sympy.Abs: "abs({})", sympy.sign: "np.sign({})", sympy.atanh: "math.atanh({})",
    sympy.cosh: "math.cosh({})", sympy.sinh: "math.sinh({})", sympy.Max: "max({})", sympy.Min: "min({})"})


def _balanced(parts: list[str], op: str) -> str:
    if len(parts) == 1:
        return parts[0]
    mid = len(parts) // 2
    return f"({_balanced(parts[:mid], op)} {op} {_balanced(parts[mid:], op)})"


def expr_code(e, d: Dialect = PYTHON) -> str:
    """``e`` as an expression of dialect ``d``."""
    if isinstance(e, Symbol):
        return e.name
    if e.is_Number:
        return d.literal(e) if not e.is_negative else f"({d.literal(e)})"
    if e is sympy.true:
        return d.true
    if isinstance(e, Add):
        terms = list(e.args)
        positives = [expr_code(t, d) for t in terms if not t.could_extract_minus_sign()]
        negatives = [expr_code(-t, d) for t in terms if t.could_extract_minus_sign()]
        if not positives:
            return f"(-{_balanced(negatives, '+')})"
        if not negatives:
            return _balanced(positives, "+")
        return f"({_balanced(positives, '+')} - {_balanced(negatives, '+')})"
    if isinstance(e, Mul):
        coeff, rest = e.as_coeff_Mul()
        if coeff == -1:
            return f"(-{expr_code(rest, d)})"
        num, den = [], []
        for f in Mul.make_args(e):
            if isinstance(f, Pow) and f.exp.is_Number and f.exp < 0:
                den.append(expr_code(Pow(f.base, -f.exp), d))
            elif isinstance(f, Rational) and not f.is_Integer and f.p in (1, -1):
                # 1/2 prints as a multiplication by 0.5, not a division
                num.append(d.literal(f))
            else:
                num.append(expr_code(f, d))
        text = _balanced(num, "*") if num else d.literal(1)
        return f"({text} / {_balanced(den, '*')})" if den else text
    if isinstance(e, Pow):
        base, exp = e.base, e.exp
        if exp == Rational(1, 2):
            return d.sqrt.format(expr_code(base, d))
        if exp == Rational(1, 3):
            return d.cbrt.format(expr_code(base, d))
        if exp == Rational(-1, 2):
            return f"({d.literal(1)} / {d.sqrt.format(expr_code(base, d))})"
        if exp.is_Integer and exp > 0:
            b = expr_code(base, d)
            return "(" + " * ".join([b] * int(exp)) + ")"
        if exp.is_Integer and exp < 0:
            return f"({d.literal(1)} / {expr_code(Pow(base, -exp), d)})"
        raise CodegenError(f"cannot print power {e}")
    if isinstance(e, (sympy.core.relational.Relational, sympy.And, sympy.Or)):
        return cond_code(e, d)                     # a condition CSE took out of a Piecewise
    if isinstance(e, Piecewise):
        (val, cond), *rest = e.args
        if cond is sympy.true:
            return expr_code(val, d)
        other = expr_code(Piecewise(*rest), d) if rest else d.nan
        return d.select(cond_code(cond, d), expr_code(val, d), other)
    if e.func in d.functions:
        template = d.functions[e.func]
        if isinstance(e, (sympy.Max, sympy.Min)) and len(e.args) > 2:
            # nest the two-argument forms (C's fmax, GLSL's max) as a balanced tree
            half = len(e.args) // 2
            return template.format(expr_code(e.func(*e.args[:half]), d), expr_code(e.func(*e.args[half:]), d)) \
                if "{}, {}" in template else template.format(", ".join(expr_code(a, d) for a in e.args))
        return template.format(*(expr_code(a, d) for a in e.args)) if template.count("{}") == len(e.args) \
            else template.format(", ".join(expr_code(a, d) for a in e.args))
    raise CodegenError(f"cannot print {type(e).__name__} in {d.name}: {e}")


def cond_code(c, d: Dialect = PYTHON) -> str:
    for cls, op in d.relations.items():
        if isinstance(c, cls):
            return f"({expr_code(c.lhs, d)} {op} {expr_code(c.rhs, d)})"
    if isinstance(c, Symbol):                       # a condition that CSE named
        return c.name
    if isinstance(c, sympy.And):
        return "(" + d.conjunction[0].join(cond_code(a, d) for a in c.args) + ")"
    if isinstance(c, sympy.Or):
        return "(" + d.conjunction[1].join(cond_code(a, d) for a in c.args) + ")"
    raise CodegenError(f"cannot print condition {c}")


def cse_assignments(exprs, prefix: str, d: Dialect = PYTHON):
    """([(temporary name, code, is_condition)], [code of each expression]) after sympy's CSE."""
    replacements, reduced = sympy.cse(list(exprs), symbols=sympy.numbered_symbols(prefix), order="none")
    assigns = [(s.name, expr_code(e, d), isinstance(e, (sympy.core.relational.Relational, sympy.And, sympy.Or)))
               for s, e in replacements]
    return assigns, [expr_code(e, d) for e in reduced]


def kernel_body(kernel, d: Dialect = PYTHON):
    """The straight-line body of a kernel: [(name, code, is_condition)] in order (each let's
    temporaries, the let itself, then the outputs' temporaries), and the outputs' code."""
    assigns = []
    for n, (sym, expr) in enumerate(kernel.lets):
        body, (value,) = cse_assignments([expr], f"l{n}_", d)
        assigns += body
        assigns.append((sym.name, value, False))
    body, values = cse_assignments(kernel.outputs, "t", d)
    return assigns + body, values
