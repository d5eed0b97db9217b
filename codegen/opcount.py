"""Operation counts of a kernel as its printers emit it (after CSE): mul, add, div, sqrt, other.

Counted on the expressions ``codegen.expressions`` prints, with its rules: a sum of n terms is n − 1
additions or subtractions, a product of n factors n − 1 multiplications (a factor −1 is a negation,
free), x^k is k − 1 multiplications, x^−k a division (after them), x^½ a square root, x^−½ a square root
and a division; functions (sin, cbrt, atan2, ...), comparisons and branches count as ``other``.
"""
from __future__ import annotations

from collections import Counter

import sympy
from sympy import Add, Mul, Piecewise, Pow, Rational

KINDS = ("mul", "add", "div", "sqrt", "other")


def _count(e, c: Counter):
    if e.is_Atom:
        return
    if isinstance(e, Add):
        c["add"] += len(e.args) - 1
    elif isinstance(e, Mul):
        coeff, _ = e.as_coeff_Mul()
        factors = [f for f in Mul.make_args(e) if f not in (-1, 1)]
        den = [f for f in factors if isinstance(f, Pow) and f.exp.is_Number and f.exp < 0]
        num = len(factors) - len(den)
        c["mul"] += max(num - 1, 0)
        if den:
            c["div"] += 1
            c["mul"] += len(den) - 1
            for f in den:
                _count(Pow(f.base, -f.exp), c)
            for f in factors:
                if f not in den:
                    _count(f, c)
            return
    elif isinstance(e, Pow):
        if e.exp == Rational(1, 2):
            c["sqrt"] += 1
        elif e.exp == Rational(-1, 2):
            c["sqrt"] += 1
            c["div"] += 1
        elif e.exp.is_Integer and e.exp > 0:
            c["mul"] += int(e.exp) - 1
        elif e.exp.is_Integer and e.exp < 0:
            c["div"] += 1
            c["mul"] += int(-e.exp) - 1
        else:
            c["other"] += 1
        _count(e.base, c)
        return
    elif isinstance(e, Piecewise):
        c["other"] += len(e.args) - 1
    else:
        c["other"] += 1                             # a function, a comparison, a boolean operator
    for a in e.args:
        _count(a, c)


def op_counts(kernel) -> dict[str, int]:
    """{kind: count} for kind in ``KINDS``: the kernel's lets and outputs after CSE (each let, then
    the outputs, as the printers group them)."""
    c: Counter = Counter()
    groups = [[e] for _, e in kernel.lets] + [list(kernel.outputs)]
    for exprs in groups:
        replacements, reduced = sympy.cse(exprs, order="none")
        for e in [r for _, r in replacements] + list(reduced):
            _count(e, c)
    return {k: c[k] for k in KINDS}


def total(counts: dict[str, int]) -> int:
    return sum(counts.values())


def describe(counts: dict[str, int]) -> str:
    """'42 mul, 30 add, 1 div, 0 sqrt, 0 other'."""
    return ", ".join(f"{counts[k]} {k}" for k in KINDS)


def table(rows) -> str:
    """A text table of [(kernel name, counts, note)]: one column per kind, the total, the note."""
    head = ("kernel", *KINDS, "total", "")
    body = [(name, *(str(counts[k]) for k in KINDS), str(total(counts)), note) for name, counts, note in rows]
    widths = [max(len(r[i]) for r in [head, *body]) for i in range(len(head))]
    fmt = lambda r: "  ".join(c.ljust(w) if i in (0, len(r) - 1) else c.rjust(w)  # noqa: E731
                              for i, (c, w) in enumerate(zip(r, widths))).rstrip()
    return "\n".join([fmt(head), *map(fmt, body)])
