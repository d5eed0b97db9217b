"""Staging passes of the kernel language's builds (``codegen.trace``): versor pruning and hoisting.

``versor_pruned`` drops result blades that vanish for every versor input (decided exactly with a Gröbner
basis of the versor conditions); ``stage`` splits a kernel with uniform inputs into the part computed
once per batch call (polynomials in the uniform inputs) and the per-row part.
"""
from __future__ import annotations

import sympy

from . import algebras
from .ir import KernelBuilder, as_expr
from .symbolic import MV


def declare(k, params):
    """[(name, type, symbols)] of ``params`` [(name, type)] declared on the KernelBuilder ``k``."""
    return [(name, typ, typ.declare(k, name)) for name, typ in params]


def versor_pruned(k, declared, mv, ret):
    """``mv`` without the blades outside ``ret`` whose coefficients vanish whenever the versor-typed
    inputs are versors (V Ṽ scalar and V e Ṽ a vector for every basis vector e): the expansion treats
    the coefficients as independent, so V x Ṽ of a symbolic 12-blade V has an e123∞0 part that is 0
    for every actual versor. Decided exactly: the coefficient reduces to 0 modulo a Gröbner basis of
    those conditions (grevlex, per input). Any other blade is left for ``ret`` to refuse."""
    allowed = {ret.algebra.mask_of(b) for b in ret.blades}
    extra = [m for m in mv.terms if m not in allowed]
    versors = [(typ, syms) for _, typ, syms in declared if typ.versor]
    if not extra or not versors:
        return mv
    gb = []
    for typ, syms in versors:
        V = k.mv(typ.blades, syms, typ.algebra)
        conditions = [c for m, c in (V * V.reverse()).terms.items() if m]
        for e in range(typ.algebra.dimension):
            S = V * MV(k.ring, {1 << e: k.ring.one}, typ.algebra) * V.reverse()
            conditions += [c for m, c in S.terms.items() if algebras.grade(m) != 1]
        if conditions:
            gb += sympy.groebner([as_expr(c) for c in conditions], *syms, order="grevlex").exprs
    gens = k.ring.symbols
    vanishing = [m for m in extra if sympy.reduced(as_expr(mv.terms[m]), gb, *gens, order="grevlex")[1] == 0]
    return MV(k.ring, {m: c for m, c in mv.terms.items() if m not in vanishing}, mv.algebra)


def stage(spec, k, declared, nums, den):
    """Split the outputs into coefficients over the uniform symbols and a row part (module docstring)."""
    ring = k.ring
    uniform = {s for name, _, syms in declared if name in spec.uniform for s in syms}
    row_idx = [i for i, s in enumerate(ring.symbols) if s not in uniform]
    if not row_idx:
        return None
    hoisted, index = [], {}

    def split(p):
        groups: dict = {}
        for mon, c in p.terms():
            rm = tuple(mon[i] for i in row_idx)
            um = tuple(0 if i in row_idx else e for i, e in enumerate(mon))
            groups[rm] = groups.get(rm, ring.zero) + ring.from_dict({um: c})
        return groups

    row_den = den is not None and any(rm != (0,) * len(row_idx) for rm in split(den))
    scale = den if (den is not None and not row_den) else None

    def row_poly(p):
        terms = []
        for rm, c in split(p).items():
            mono = sympy.Mul(*(ring.symbols[i] ** e for i, e in zip(row_idx, rm)))
            if c.is_ground and scale is None:
                terms.append(as_expr(c) * mono)
                continue
            key = tuple(sorted(c.items()))
            if key not in index:
                index[key] = len(hoisted)
                hoisted.append(c)
            terms.append(sympy.Symbol(f"hoisted{index[key]}", real=True) * mono)
        return sympy.Add(*terms)

    rows = [row_poly(n) for n in nums]
    if row_den:
        d = row_poly(den)
        rows = [sympy.Mul(r, sympy.Pow(d, -1)) for r in rows]
    if not hoisted:
        return None
    params = [(name, typ) for name, typ, _ in declared]
    u = KernelBuilder(f"_{spec.name}_uniform", f"The part of ``{spec.name}`` that depends only on "
                      f"{', '.join(spec.uniform)}: computed once per batch call.")
    declare(u, [p for p in params if p[0] in spec.uniform])
    values = [as_expr(c) for c in hoisted]
    if scale is not None:
        (inv,) = u.intermediate("inv_weight")
        u.let(inv, 1 / as_expr(scale))
        values = [v * inv for v in values]
    u.output([f"hoisted[{j}]" for j in range(len(values))], values)
    r = KernelBuilder(f"_{spec.name}_row", f"The per-row part of ``{spec.name}``, given ``_{spec.name}_uniform``.")
    if len(hoisted) == 1:
        r.scalar("hoisted0")
    else:
        r.array("hoisted", len(hoisted))
    declare(r, [p for p in params if p[0] not in spec.uniform])
    r.output([f"out[{j}]" for j in range(len(rows))], rows)
    return u.build(), r.build()
