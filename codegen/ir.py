"""Kernel IR: what a kernel takes, the intermediate values it defines, and what it returns.

A kernel is built once, symbolically, by a function of the catalogue:

    k = KernelBuilder("gp_versor_versor", "Geometric product a b of two versors.")
    a = k.multivector("a", VERSOR)            # declares a_s, a_e12, ... as symbols
    b = k.multivector("b", VERSOR)
    k.output_multivector("ab", k.mv(VERSOR, a) * k.mv(VERSOR, b), VERSOR)
    kernel = k.build()

The IR is printer-independent: inputs (names, kinds, sizes), ``lets`` (symbol = expression, in
order) and flat output expressions. Printers (numba now; cuda/C later) only read ``Kernel``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import sympy
from sympy import QQ, Symbol
from sympy.polys.rings import PolyRing

from . import algebra
from .errors import CodegenError  # noqa: F401 (re-exported: codegen.ir.CodegenError)
from .symbolic import MV


@dataclass(frozen=True)
class Input:
    name: str
    kind: str               # "multivector" | "array" | "scalar"
    symbols: tuple           # the symbols the kernel unpacks this input into
    labels: tuple            # blade names or component indices, for docs


@dataclass(frozen=True)
class Kernel:
    name: str
    doc: str
    inputs: tuple
    lets: tuple              # ((Symbol, Expr), ...) in dependency order
    outputs: tuple           # (Expr, ...)
    output_labels: tuple     # one label per output
    output_shape: tuple      # shape of the returned array, e.g. (12,) or (3, 4)
    expansion: tuple = field(default=())   # readable "label = expression" lines

    @property
    def spec_text(self) -> str:
        """A canonical text of the spec (for hashing): inputs, lets and outputs."""
        parts = [self.name, repr([(i.name, i.kind, [str(s) for s in i.symbols]) for i in self.inputs])]
        parts += [f"{s} = {sympy.srepr(e)}" for s, e in self.lets]
        parts += [sympy.srepr(e) for e in self.outputs]
        return "\n".join(parts)


def renamed(kernel: Kernel, legal) -> Kernel:
    """``kernel`` with every input, input symbol and let named ``legal(name)`` (a printer's legal,
    unreserved identifier for it; the name itself when it is one): the same object when none changes."""
    symbols = [s for i in kernel.inputs for s in i.symbols] + [s for s, _ in kernel.lets]
    renames = {s: Symbol(legal(s.name), real=True) for s in symbols if legal(s.name) != s.name}
    inputs = tuple(replace(i, name=legal(i.name), symbols=tuple(renames.get(s, s) for s in i.symbols))
                   for i in kernel.inputs)
    if not renames and all(i.name == j.name for i, j in zip(inputs, kernel.inputs)):
        return kernel
    return replace(kernel, inputs=inputs, lets=tuple((renames.get(s, s), e.xreplace(renames)) for s, e in kernel.lets),
                   outputs=tuple(e.xreplace(renames) for e in kernel.outputs))


class KernelBuilder:
    """Declares a kernel's symbols, then builds its outputs with symbolic multivectors."""

    def __init__(self, name: str, doc: str):
        self.name, self.doc = name, doc
        self._symbols: list[Symbol] = []
        self._inputs: list[Input] = []
        self._lets: list[tuple[Symbol, sympy.Expr]] = []
        self._declared_lets: list[Symbol] = []
        self._outputs: list = []
        self._labels: list[str] = []
        self._shape: tuple = ()
        self._ring: PolyRing | None = None

    # -- declarations (before the first use of ``ring``) -----------------------------------------
    def _declare(self, names, late_ok=False):
        syms = tuple(Symbol(n, real=True) for n in names)
        if self._ring is not None:
            # after the ring exists a symbol can only appear in expressions, not in products
            if not late_ok:
                raise CodegenError(f"{self.name}: declare inputs before building expressions")
            return syms
        self._symbols += syms
        return syms

    def multivector(self, name: str, blades: tuple[str, ...]):
        syms = self._declare([f"{name}_{b}" for b in blades])
        self._inputs.append(Input(name, "multivector", syms, tuple(blades)))
        return syms

    def array(self, name: str, size: int):
        syms = self._declare([f"{name}{i}" for i in range(size)])
        self._inputs.append(Input(name, "array", syms, tuple(range(size))))
        return syms

    def scalar(self, name: str):
        (sym,) = self._declare([name])
        self._inputs.append(Input(name, "scalar", (sym,), ("",)))
        return sym

    def intermediate(self, *names: str):
        """Symbols whose value ``let`` gives later. Declared before the first product, they can
        take part in products; declared after, only in expressions."""
        syms = self._declare(names, late_ok=True)
        self._declared_lets += syms
        return syms

    # -- building -------------------------------------------------------------------------------
    @property
    def ring(self) -> PolyRing:
        if self._ring is None:
            self._ring = PolyRing(self._symbols, QQ)
        return self._ring

    def poly(self, sym):
        return self.ring(sym)

    def mv(self, blades, values, alg=algebra.cga) -> MV:
        """A symbolic multivector of ``alg`` with ``values`` (symbols, numbers or polynomials) on ``blades``."""
        return MV.from_coefficients(self.ring, blades, [self.ring(v) if not hasattr(v, "ring") else v
                                                        for v in values], alg)

    def let(self, sym: Symbol, value):
        """Define an intermediate symbol (in the order the kernel computes it)."""
        if sym not in self._declared_lets:
            raise CodegenError(f"{self.name}: {sym} was not declared with intermediate()")
        self._lets.append((sym, as_expr(value)))

    def output_multivector(self, label: str, mv: MV, blades: tuple[str, ...], scale=None):
        """Return the coefficients of ``mv`` on ``blades``; any other nonzero blade is an error."""
        masks = [algebra.mask_of(b) for b in blades]
        extra = set(mv.terms) - set(masks)
        if extra:
            raise CodegenError(f"{self.name}: result has blades {[algebra.blade_display(m) for m in sorted(extra)]}"
                               f" outside the declared type {blades}")
        for b, m in zip(blades, masks):
            value = as_expr(mv.terms.get(m, 0))
            self._outputs.append(value if scale is None else value * scale)
            self._labels.append(f"{label}[{algebra.blade_display(m)}]")
        self._shape = (len(self._outputs),)

    def output(self, labels, values, shape=None):
        for lab, v in zip(labels, values):
            self._outputs.append(as_expr(v))
            self._labels.append(lab)
        self._shape = shape or (len(self._outputs),)

    def eliminate(self, name: str):
        """Drop an input the outputs no longer depend on (the hoist pass removes the point)."""
        self._inputs = [i for i in self._inputs if i.name != name]

    def build(self) -> Kernel:
        known = {s for i in self._inputs for s in i.symbols} | set(self._declared_lets)
        for e in [*self._outputs, *(e for _, e in self._lets)]:
            unknown = e.free_symbols - known
            if unknown:
                raise CodegenError(f"{self.name}: expressions use undeclared or eliminated {sorted(map(str, unknown))}")
        defined = {s for s, _ in self._lets}
        missing = [s for s in self._declared_lets if s not in defined]
        if missing:
            raise CodegenError(f"{self.name}: intermediates never defined: {missing}")
        expansion = tuple(f"{s} = {pretty(e)}" for s, e in self._lets)
        expansion += tuple(f"{lab} = {pretty(e)}" for lab, e in zip(self._labels, self._outputs))
        return Kernel(self.name, self.doc, tuple(self._inputs), tuple(self._lets), tuple(self._outputs),
                      tuple(self._labels), self._shape, expansion)


def as_expr(value):
    """A sympy expression from a ring polynomial, a number or an expression."""
    if hasattr(value, "as_expr") and hasattr(value, "ring"):
        return value.as_expr()
    return sympy.sympify(value)


def pretty(expr) -> str:
    """Compact one-line text of an expression for docstrings (``sstr``, no line breaks)."""
    return sympy.sstr(expr, order="none").replace("\n", " ")
