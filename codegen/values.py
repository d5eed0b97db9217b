"""The values of the kernel language (``codegen/language.py``): multivectors traced through a kernel.

A ``Value`` wraps a multivector of the ring of the kernel being built (``building``): a symbolic
``codegen.symbolic.MV`` at build time, or a numeric one of a backend (``codegen.verify_clifford``) when
the same function is evaluated on clifford multivectors. Operators, constants (``Constant``) and the
scalar functions (``_apply``) are defined here; the types and ``@kernel`` are in ``language.py``.
Importing this module does not import sympy.
"""
from __future__ import annotations

import numbers
from fractions import Fraction

from . import algebras

_RINGS: list = []          # the polynomial ring of the kernel being built (a stack; empty outside a build)


def _error(message):
    from .ir import CodegenError      # ir imports sympy: only at build time
    return CodegenError(message)


def _ring():
    if not _RINGS:
        raise _error("cga values exist only while `cgaskin build` traces a kernel")
    return _RINGS[-1]


class building:
    """Context manager: values and constants made inside use ``ring`` (the kernel's symbols), or a
    numeric backend with ``scalar_mv``/``basis_mv`` (``codegen.verify``: clifford multivectors)."""

    def __init__(self, ring):
        self.ring = ring

    def __enter__(self):
        _RINGS.append(self.ring)

    def __exit__(self, *exc):
        _RINGS.pop()


def _number(x):
    """An exact Fraction of a Python or numpy number (floats exactly, as their binary value)."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        return None
    return Fraction(x) if isinstance(x, numbers.Rational) else Fraction(float(x))


def _scalar_mv(value: Fraction):
    ring = _ring()
    if hasattr(ring, "scalar_mv"):                   # a numeric backend (codegen.verify: clifford values)
        return ring.scalar_mv(value)
    from sympy import QQ
    from .symbolic import MV
    return MV(ring, {0: ring(QQ(value.numerator, value.denominator))})


class Value:
    """A symbolic multivector while a kernel is traced (wraps ``symbolic.MV``)."""

    __slots__ = ("_mv",)

    def __init__(self, mv):
        self._mv = mv

    @property
    def mv(self):
        return self._mv

    @property
    def blades(self) -> tuple[str, ...]:
        """Display names of the blades with a nonzero coefficient (the value's type)."""
        return tuple(self.mv.algebra.blade_display(m) for m in self.mv.blades)

    def _as_mv(self, other):
        if isinstance(other, Value):
            return other.mv
        q = _number(other)
        return None if q is None else _scalar_mv(q)

    def _binary(self, other, op, swap=False):
        b = self._as_mv(other)
        if b is None:
            return NotImplemented
        a = self.mv
        if hasattr(a, "ring") and hasattr(b, "ring") and a.ring != b.ring:
            a, b = _functions().unify(a, b)          # one holds scalar-function atoms (codegen.functions)
        return Value(op(b, a) if swap else op(a, b))

    # products
    def __mul__(self, other):
        return self._binary(other, lambda a, b: a * b)

    def __rmul__(self, other):
        return self._binary(other, lambda a, b: a * b, swap=True)

    def __xor__(self, other):
        return self._binary(other, lambda a, b: a ^ b)

    def __rxor__(self, other):
        return self._binary(other, lambda a, b: a ^ b, swap=True)

    def __or__(self, other):
        """Left contraction self ⌋ other."""
        return self._binary(other, lambda a, b: a.lc(b))

    def __ror__(self, other):
        return self._binary(other, lambda a, b: a.lc(b), swap=True)

    # linear structure
    def __add__(self, other):
        return self._binary(other, lambda a, b: a + b)

    def __radd__(self, other):
        return self._binary(other, lambda a, b: a + b, swap=True)

    def __sub__(self, other):
        return self._binary(other, lambda a, b: a - b)

    def __rsub__(self, other):
        return self._binary(other, lambda a, b: a - b, swap=True)

    def __truediv__(self, other):
        q = _number(other)
        return self * (1 / q) if q is not None else self * _apply("inv", other)

    def __rtruediv__(self, other):
        return _apply("inv", self) * other

    def __abs__(self):
        return _apply("abs", self)

    __lt__, __le__, __gt__, __ge__ = (lambda a, b, op=op: _apply(op, a, b) for op in ("<", "<=", ">", ">="))

    def __neg__(self):
        return Value(-self.mv)

    def __pos__(self):
        return self

    # involutions and projections
    def __invert__(self):
        return Value(self.mv.reverse())

    def reverse(self):
        return ~self

    def dual(self):
        """X I⁻¹ with I = e123∞0."""
        return Value(self.mv.dual())

    def grade(self, *grades: int):
        return Value(self.mv.grade(*grades))

    def __bool__(self):
        raise _error("a traced multivector has no truth value: kernels are straight-line code")

    def __repr__(self):
        return f"Value({self.mv!r})"


def as_value(x) -> Value | None:
    """``x`` as a traced value: a Value itself, a number as a scalar; None for anything else."""
    if isinstance(x, Value):
        return x
    q = _number(x)
    return None if q is None else Value(_scalar_mv(q))


def _functions():
    from . import functions                         # sympy: only at build time
    return _ring() if hasattr(_ring(), "function") else functions   # a numeric backend has its own


def _apply(name, *args):
    """``cga.sqrt(x)`` etc. (a scalar value), ``x > y`` (a condition), ``cga.where(condition, a, b)``:
    a where the condition holds, else b, blade by blade (``codegen.functions``)."""
    values = [a if name == "where" and not i else as_value(a) for i, a in enumerate(args)]
    if None in values:
        raise TypeError(f"cga.{name} takes cga values or numbers, not {[type(a).__name__ for a in args]}")
    out = _functions().function(name, *(v.mv if isinstance(v, Value) else v for v in values))
    return Value(out) if name[0].isalpha() else out


class Constant(Value):
    """A basis blade (``cga.e1``, ``cga.einf``, ``pga.e0`` ...) of ``algebra``, made in the ring of the
    kernel being traced."""

    __slots__ = ("name", "algebra", "space")

    def __init__(self, name: str, algebra=algebras.cga, space: str = "cga"):
        super().__init__(None)
        self.name, self.algebra, self.space = name, algebra, space

    @property
    def mv(self):
        ring = _ring()
        if hasattr(ring, "basis_mv"):                   # a numeric backend (codegen.verify)
            return ring.basis_mv(self.name, self.algebra)
        from .symbolic import basis
        return basis(ring, self.name, self.algebra)

    def __repr__(self):
        return f"{self.space}.{self.name}"
