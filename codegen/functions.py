"""Scalar functions of traced kernel values (``cga.sqrt``, ``cos``, ..., ``cga.where``), symbolically.

A product expansion stays polynomial; ``sqrt(p)``, ``cos(p)``, ``1/p`` or a ``where`` branch is not, so
each such result becomes a new generator of the polynomial ring (an *atom*, e.g. ``_f0`` standing for
``sqrt(x0**2 + x1**2)``): values holding atoms live in an extension of the kernel's ring, products keep
expanding and pruning exactly, and ``final`` writes the atoms back as expressions (the printer turns
them into ``math.sqrt``, ``math.cos``, conditional expressions; CSE shares repeats). The same
expression always gives the same atom, so ``sqrt(x) - sqrt(x)`` is 0. ``NUMERIC`` and ``OPERATORS``
are the float versions, for ``codegen.verify``'s clifford backend.
"""
from __future__ import annotations

import math
import operator

import sympy
from sympy import QQ, Symbol
from sympy.polys.rings import PolyRing

from .symbolic import MV

SYMBOLIC = {"sqrt": sympy.sqrt, "cos": sympy.cos, "sin": sympy.sin, "exp": sympy.exp, "log": sympy.log,
            "atan2": sympy.atan2, "abs": sympy.Abs, "inv": lambda x: 1 / x}
NUMERIC = {"sqrt": math.sqrt, "cos": math.cos, "sin": math.sin, "exp": math.exp, "log": math.log,
           "atan2": math.atan2, "abs": abs, "inv": lambda x: 1 / x}
OPERATORS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
_RELATIONS = {"<": sympy.Lt, "<=": sympy.Le, ">": sympy.Gt, ">=": sympy.Ge}

_DEFINITIONS: dict = {}          # atom symbol -> its expression (in input symbols and earlier atoms)
_ATOMS: dict = {}                # expression -> atom symbol


def _union(*rings):
    symbols = list(rings[0].symbols)
    for r in rings[1:]:
        symbols += [s for s in r.symbols if s not in symbols]
    return PolyRing(tuple(symbols), QQ) if len(symbols) > rings[0].ngens else rings[0]


def unify(*mvs):
    """The multivectors over one ring (the union of their generators)."""
    ring = _union(*(m.ring for m in mvs))
    return [m if m.ring == ring else MV(ring, {k: c.set_ring(ring) for k, c in m.terms.items()}, m.algebra)
            for m in mvs]


def _poly(expr, ring):
    """(ring, element) for ``expr``: a polynomial of ``ring`` where it is one, else an atom. A constant
    (``atan2(0, -1)`` is pi) is its float64 value, exactly."""
    if not expr.free_symbols and not expr.is_Rational:
        expr = sympy.Rational(float(expr))
    try:
        return ring, ring.from_expr(expr)
    except (ValueError, TypeError, sympy.CoercionFailed):
        pass
    sym = _ATOMS.get(expr)
    if sym is None:
        sym = _ATOMS[expr] = Symbol(f"_f{len(_DEFINITIONS)}", real=True)
        _DEFINITIONS[sym] = expr
    if sym not in ring.symbols:
        ring = PolyRing(ring.symbols + (sym,), QQ)
    return ring, ring(sym)


def _scalar(name, mv):
    blades = [mv.algebra.blade_display(m) for m in mv.blades if m]
    if blades:
        what = ("division by a multivector" if name == "inv" else f"cga.{name} of a multivector" if name[0].isalpha()
                else f"comparison {name} of a multivector")
        raise ValueError(f"{what}: only scalar values are allowed, this one has blades {', '.join(blades)}")
    return mv


def function(name, *args):
    """``name`` ("sqrt", ..., "inv") of scalar multivectors; a relation for "<" ... ">="; "where"."""
    if name == "where":
        return where(*args)
    mvs = unify(*(_scalar(name, m) for m in args))
    if name in _RELATIONS:          # a sympy relation between the scalar parts, atoms unexpanded
        return _RELATIONS[name](*(m[0].as_expr() for m in mvs))
    ring, p = _poly(SYMBOLIC[name](*(m[0].as_expr() for m in mvs)), mvs[0].ring)
    return MV(ring, {0: p})


def where(condition, a, b):
    """Blade by blade: a's coefficient where ``condition`` holds, else b's."""
    if not isinstance(condition, sympy.logic.boolalg.Boolean):
        raise TypeError("cga.where needs a condition such as x > y on scalar values, "
                        f"not {type(condition).__name__}")
    a, b = unify(a, b)
    ring, terms = a.ring, {}
    for m in set(a.terms) | set(b.terms):
        ea, eb = a[m].as_expr(), b[m].as_expr()
        ring, terms[m] = _poly(ea if ea == eb else sympy.Piecewise((ea, condition), (eb, True)), ring)
    return MV(ring, {m: c.set_ring(ring) for m, c in terms.items()}, a._algebra_with(b))


def final(base, polys):
    """Each polynomial in ``base`` (the kernel's ring) where it uses no atom, else its expression."""
    if all(p.ring == base for p in polys):
        return polys
    out = []
    for p in polys:
        n = base.ngens
        if all(not any(mon[n:]) for mon in p.keys()):
            out.append(base.from_dict({mon[:n]: c for mon, c in p.items()}))
            continue
        expr = p.as_expr()
        while atoms := expr.free_symbols & _DEFINITIONS.keys():
            expr = expr.xreplace({s: _DEFINITIONS[s] for s in atoms})
        out.append(expr)
    return out


def magnitude(expr):
    """A bound on the scale of float64 rounding in ``expr``: the sum of its terms' magnitudes through
    sums and products, |f(...)| for anything else (roots, functions, branches)."""
    if expr.is_Symbol or expr.is_Number:
        return sympy.Abs(expr)
    if expr.is_Add or expr.is_Mul:
        return expr.func(*(magnitude(a) for a in expr.args))
    if expr.is_Pow and expr.exp.is_Integer and expr.exp > 0:
        return magnitude(expr.base) ** expr.exp
    return sympy.Abs(expr)
