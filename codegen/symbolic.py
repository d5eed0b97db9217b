"""Symbolic multivectors: {blade mask: polynomial} over a sympy sparse polynomial ring, in any
``codegen.algebras.Algebra`` (G(4,1) in the null basis unless told otherwise).

Products expand through the numeric tables of ``algebra`` and drop every coefficient that is
identically zero, so the blade set of a result *is* its type (the prune pass happens as we go).
Polynomials stay in sympy's ``ring`` representation (fast, no ``simplify``); kernels convert them
to expressions only at the end, for CSE and printing.
"""
from __future__ import annotations

from fractions import Fraction

from sympy import QQ, Rational

from . import algebra, algebras
from .errors import CodegenError


def _qq(c):
    return QQ(c.numerator, c.denominator) if isinstance(c, Fraction) else c


class MV:
    """A symbolic multivector of ``algebra`` (default: G(4,1) in the null basis).

    A multivector with only a scalar part is the same in every algebra: it takes the algebra of the
    other operand of a sum or product, so numbers and scalar functions need no algebra of their own."""

    __slots__ = ("ring", "terms", "algebra")

    def __init__(self, ring, terms=None, algebra=algebras.cga):
        self.ring = ring
        self.terms = {m: c for m, c in (terms or {}).items() if c}
        self.algebra = algebra

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def from_coefficients(cls, ring, blades, coefficients, algebra=algebras.cga):
        return cls(ring, {algebra.mask_of(b) if isinstance(b, str) else b: ring(c)
                          for b, c in zip(blades, coefficients)}, algebra)

    @classmethod
    def scalar(cls, ring, value):
        return cls(ring, {0: ring(value)})

    def __getitem__(self, blade):
        mask = self.algebra.mask_of(blade) if isinstance(blade, str) else blade
        return self.terms.get(mask, self.ring.zero)

    @property
    def blades(self) -> tuple[int, ...]:
        return tuple(sorted(self.terms, key=lambda m: (algebras.grade(m), self.algebra.vectors_of(m))))

    def _algebra_with(self, other):
        """The algebra of a sum or product with ``other`` (a scalar-only operand adopts the other's)."""
        if self.algebra == other.algebra or not set(other.terms) - {0}:
            return self.algebra
        if not set(self.terms) - {0}:
            return other.algebra
        raise CodegenError(f"a value of {self.algebra} meets one of {other.algebra}: one kernel, one algebra")

    # -- linear structure ---------------------------------------------------------------------
    def __add__(self, other):
        other = self._coerce(other)
        terms = dict(self.terms)
        for m, c in other.terms.items():
            terms[m] = terms.get(m, self.ring.zero) + c
        return MV(self.ring, terms, self._algebra_with(other))

    __radd__ = __add__

    def __neg__(self):
        return MV(self.ring, {m: -c for m, c in self.terms.items()}, self.algebra)

    def __sub__(self, other):
        return self + (-self._coerce(other))

    def __rsub__(self, other):
        return self._coerce(other) - self

    def scale(self, factor):
        factor = self.ring(_qq(factor)) if not hasattr(factor, "ring") else factor
        return MV(self.ring, {m: c * factor for m, c in self.terms.items()}, self.algebra)

    def _coerce(self, other):
        if isinstance(other, MV):
            return other
        return MV.scalar(self.ring, _qq(other) if isinstance(other, Fraction) else other)

    # -- products -----------------------------------------------------------------------------
    def _product(self, other, kind):
        other = self._coerce(other)
        alg = self._algebra_with(other)
        table = alg.product_table(kind)
        zero = self.ring.zero
        out: dict[int, object] = {}
        for a, ca in self.terms.items():
            for b, cb in other.terms.items():
                entry = table[a, b]
                if not entry:
                    continue
                ab = ca * cb
                for m, k in entry:
                    out[m] = out.get(m, zero) + ab * _qq(k)
        return MV(self.ring, out, alg)

    def __mul__(self, other):
        if isinstance(other, MV):
            return self._product(other, "gp")
        return self.scale(other)

    def __rmul__(self, other):
        return self.scale(other)

    def __xor__(self, other):
        return self._product(other, "outer")

    def lc(self, other):
        """Left contraction self ⌋ other."""
        return self._product(other, "lcontract")

    # -- involutions and projections ----------------------------------------------------------
    def reverse(self):
        return MV(self.ring, {m: c * algebras.reverse_sign(m) for m, c in self.terms.items()}, self.algebra)

    def grade(self, *grades):
        return MV(self.ring, {m: c for m, c in self.terms.items() if algebras.grade(m) in grades}, self.algebra)

    def dual(self):
        """X I⁻¹ with I the pseudoscalar (in CGA e123∞0 = e1 e2 e3 e+ e−, I² = −1, so I⁻¹ = −I)."""
        alg = self.algebra
        square = MV(self.ring, {alg.pseudoscalar: self.ring.one}, alg)
        square = (square * square)[0]
        if not square:
                raise CodegenError(f"dual(): the pseudoscalar of {alg} squares to 0 (a degenerate metric), so "
                               f"X I⁻¹ does not exist; write the complement you mean with explicit blades")
        return self * MV(self.ring, {alg.pseudoscalar: self.ring.one / square}, alg)

    def __repr__(self):
        return " + ".join(f"({c.as_expr()})*{self.algebra.blade_display(m)}"
                          for m, c in sorted(self.terms.items())) or "0"


def basis(ring, name, alg=algebras.cga):
    """The basis blade ``name`` (e.g. 'e1', 'ei', 'eio') of ``alg`` as a multivector with coefficient 1."""
    return MV(ring, {alg.mask_of(name): ring.one}, alg)


def up(ring, x):
    """Conformal point x + ½|x|² e∞ + e0 from three ring elements."""
    x1, x2, x3 = x
    return MV(ring, {1: x1, 2: x2, 4: x3,
                     algebra.mask_of("ei"): (x1 * x1 + x2 * x2 + x3 * x3) * QQ(1, 2),
                     algebra.mask_of("eo"): ring.one})


HALF = Rational(1, 2)
