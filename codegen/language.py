"""The kernel language: CGA kernels written as plain Python functions over typed multivectors.

    from cgaskin.codegen import cga, kernel

    @kernel
    def reflect(plane: cga.Plane, x: cga.Point) -> cga.Point:
        '''Reflect a point in a plane.'''
        return -plane * x * plane

    @kernel(uniform=("V",))
    def move(V: cga.Versor, x: cga.Point) -> cga.Point:
        return V * x * ~V

Nothing runs at import: ``@kernel`` only records the function (a ``KernelSpec``). At build time
(``codegen.catalogue_build.build_catalogue``, ``cgaskin build --catalogue FILE --out DIR``) each input is
declared by its type, the function is called once on symbolic values, and the result, whose blade set
is its type (coefficients that are identically zero are pruned as the products expand), must fit the
declared return type, else ``CodegenError`` names the kernel and the extra blades.

Types (attributes of ``cga``; a type is a blade set of ``codegen.algebra``'s null basis e1 e2 e3 e∞ e0):
    Scalar   float                                    Vector  (e1, e2, e3)
    Point    Euclidean (3,) array: up-projected on entry (x + ½x² e∞ + e0), down-projected on return
             (Euclidean part over the e0 coefficient)
    Plane    (n1, n2, n3, d) = n + d e∞ (dual plane {x : n·x = d})
    Sphere   (c1, c2, c3, c∞, c0) on e1 e2 e3 e∞ e0 (dual sphere up(c) − ½r² e∞)
    Line     dual line (bivector) on e12 e13 e23 e1∞ e2∞ e3∞ (e.g. the meet plane1 ^ plane2)
    Rotor    (s, e12, e13, e23)    Motor  (+ e1∞, e2∞, e3∞, e123∞)    Versor  (+ e∞0, e12∞0, e13∞0, e23∞0)
    Multivector["e1", "e2", "ei", ...]   any blade set, in the order given
Constants ``cga.e1, cga.e2, cga.e3, cga.einf, cga.eo``. Operators on values: ``*`` geometric product,
``^`` outer, ``|`` inner = LEFT CONTRACTION a ⌋ b, ``~`` reverse, unary ``-``, ``+``, ``-``, scalar
``*`` and ``/`` by numbers; methods ``.dual()`` (X I⁻¹, I = e123∞0), ``.grade(k, ...)``, ``.reverse()``.
Python's precedence applies: unary ``-``/``~`` bind tightest, then ``*`` ``/``, then ``+`` ``-``, then
``^``, then ``|`` — so ``a ^ b + c`` is ``a ^ (b + c)``: parenthesise. On scalar values (numbers too):
``cga.sqrt cos sin exp log abs atan2``, ``/``, and ``x > y`` (``<`` ``>=`` ``<=``), a condition for
``cga.where(cond, a, b)`` (blade by blade; ``codegen.functions``). Not in this language yet: division by
a multivector, ``if`` (kernels are straight-line code), a value from several outputs.

Versor types (Rotor, Motor, Versor) are taken to hold versors. The expansion treats their coefficients
as independent, so ``V * x * ~V`` of a symbolic 12-blade V has an e123∞0 part that is zero for every
actual versor; such a blade outside the return type is dropped only when its coefficient reduces to 0
modulo a Gröbner basis of the versor conditions (V Ṽ scalar, V e Ṽ a vector for each basis vector e),
and the kernel's docstring says so. The same product of a ``cga.Multivector[...]`` is an error.

``cga`` is also the algebra itself: an ``Algebra`` equal to ``codegen.algebras.cga`` (same tables), with
the types and constants above as attributes. Importing this module does not import sympy.
"""
from __future__ import annotations

import functools
import inspect
import numbers
import typing
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
        return tuple(algebras.cga.blade_display(m) for m in self.mv.blades)

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
    """A basis blade (``cga.e1``, ``cga.einf`` ...), made in the ring of the kernel being traced."""

    __slots__ = ("name",)

    def __init__(self, name: str):
        super().__init__(None)
        self.name = name

    @property
    def mv(self):
        ring = _ring()
        if hasattr(ring, "basis_mv"):                   # a numeric backend (codegen.verify)
            return ring.basis_mv(self.name)
        from .symbolic import basis
        return basis(ring, self.name)

    def __repr__(self):
        return f"cga.{self.name}"


class Type:
    """A blade set: inputs of this type are (len(blades),) arrays of coefficients in that order."""

    kind = "multivector"

    def __init__(self, name: str, blades, versor: bool = False):
        self.name = name
        self.versor = versor          # values are versors: V Ṽ is a scalar, V e Ṽ a vector
        self.blades = tuple(algebras.cga.blade_name(algebras.cga.mask_of(b)) for b in blades)
        if len(set(self.blades)) != len(self.blades):
            raise algebras.InvalidAlgebraError(f"{name}: a blade is repeated in {self.blades}")

    @property
    def size(self) -> int:
        return len(self.blades)

    def describe(self) -> str:
        shown = ", ".join(algebras.cga.blade_display(algebras.cga.mask_of(b)) for b in self.blades)
        return f"{self.name} ({shown})"

    def declare(self, k, arg: str):
        """Declare the input ``arg`` on ``ir.KernelBuilder`` k; returns its symbols."""
        return k.multivector(arg, self.blades)

    def value(self, k, symbols) -> Value:
        return Value(k.mv(self.blades, symbols))

    def _check(self, kernel: str, mv, allowed):
        masks = {algebras.cga.mask_of(b) for b in allowed}
        extra = [m for m in mv.blades if m not in masks]
        if extra:
            names = ", ".join(algebras.cga.blade_display(m) for m in extra)
            raise _error(f"kernel {kernel!r}: the result has blades {names} outside its return type "
                         f"{self.describe()}")

    def outputs(self, kernel: str, mv):
        """(labels, numerator polynomials, denominator polynomial or None) of a result of this type."""
        self._check(kernel, mv, self.blades)
        return ([algebras.cga.blade_display(algebras.cga.mask_of(b)) for b in self.blades],
                _functions().final(_ring(), [mv[b] for b in self.blades]), None)

    def __repr__(self):
        return f"cga.{self.name}"


class ScalarType(Type):
    kind = "scalar"

    def declare(self, k, arg):
        return (k.scalar(arg),)


class PointType(Type):
    """A point passed as its Euclidean (3,) coordinates; the algebra sees up(x)."""

    kind = "point"

    def __init__(self):
        super().__init__("Point", ("e1", "e2", "e3", "ei", "eo"))

    @property
    def size(self) -> int:
        return 3

    def describe(self) -> str:
        return "Point (e1, e2, e3, e∞, e0: up-projected from / down-projected to (3,))"

    def declare(self, k, arg):
        return k.array(arg, 3)

    def value(self, k, symbols):
        from .symbolic import up
        return Value(up(k.ring, [k.poly(s) for s in symbols]))

    def outputs(self, kernel, mv):
        self._check(kernel, mv, self.blades)
        weight = mv["eo"]
        if not weight:
            raise _error(f"kernel {kernel!r}: the result has no e0 part, so it is not a point to down-project")
        *nums, weight = _functions().final(_ring(), [mv["e1"], mv["e2"], mv["e3"], weight])
        return ["x[0]", "x[1]", "x[2]"], nums, weight


class _MultivectorFactory:
    """``cga.Multivector["e1", "e2", "ei"]``: the type of any blade set, in the order given."""

    def __getitem__(self, blades):
        blades = (blades,) if isinstance(blades, str) else tuple(blades)
        shown = ", ".join(algebras.cga.blade_display(algebras.cga.mask_of(b)) for b in blades)
        return Type(f"Multivector[{shown}]", blades)

    def __repr__(self):
        return "cga.Multivector"


_VERSOR = ("s", "e12", "e13", "e23", "e1i", "e2i", "e3i", "e123i", "eio", "e12io", "e13io", "e23io")


class ConformalAlgebra(algebras.Algebra):
    """G(4,1) in the null basis (equal to ``codegen.algebras.cga``, sharing its tables) with the kernel
    language's types and constants as attributes."""

    Scalar = ScalarType("Scalar", ("s",))
    Vector = Type("Vector", ("e1", "e2", "e3"))
    Point = PointType()
    Plane = Type("Plane", ("e1", "e2", "e3", "ei"))
    Sphere = Type("Sphere", ("e1", "e2", "e3", "ei", "eo"))
    Line = Type("Line", ("e12", "e13", "e23", "e1i", "e2i", "e3i"))
    Rotor = Type("Rotor", _VERSOR[:4], versor=True)
    Motor = Type("Motor", _VERSOR[:8], versor=True)
    Versor = Type("Versor", _VERSOR, versor=True)
    Multivector = _MultivectorFactory()
    e1, e2, e3, einf, eo = (Constant(n) for n in ("e1", "e2", "e3", "ei", "eo"))
    sqrt, cos, sin, exp, log, abs, atan2, where = (staticmethod(functools.partial(_apply, n)) for n in
                                                   ("sqrt", "cos", "sin", "exp", "log", "abs", "atan2", "where"))

    def __init__(self):
        super().__init__(signature=(4, 1, 0), basis="null")
        self._tables = algebras.cga._tables


cga = ConformalAlgebra()


class KernelSpec:
    """A kernel recorded by ``@kernel``: the function, its name, docstring and uniform inputs.

    Calling it calls the function (so kernels can use each other while traced)."""

    def __init__(self, fn, uniform=()):
        self.fn = fn
        self.name = fn.__name__
        self.doc = inspect.getdoc(fn) or ""
        self.uniform = (uniform,) if isinstance(uniform, str) else tuple(uniform)
        functools.update_wrapper(self, fn)

    def __call__(self, *args, **kwargs):
        return self.fn(*args, **kwargs)

    def signature(self):
        """([(argument name, Type)], return Type), from the annotations (strings are resolved)."""
        try:
            hints = typing.get_type_hints(self.fn)
        except Exception as exc:  # noqa: BLE001 - any failure to resolve is the catalogue's to fix
            raise _error(f"kernel {self.name!r}: cannot resolve its annotations ({exc})") from exc
        params = []
        for p in inspect.signature(self.fn).parameters.values():
            if p.kind not in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD):
                raise _error(f"kernel {self.name!r}: argument {p.name!r} must be a plain positional argument")
            if not isinstance(hints.get(p.name), Type):
                raise _error(f"kernel {self.name!r}: argument {p.name!r} needs a cga type annotation "
                             f"(e.g. cga.Point), got {hints.get(p.name)!r}")
            params.append((p.name, hints[p.name]))
        ret = hints.get("return")
        if not isinstance(ret, Type):
            raise _error(f"kernel {self.name!r}: the return needs a cga type annotation, got {ret!r}")
        unknown = [u for u in self.uniform if u not in dict(params)]
        if unknown:
            raise _error(f"kernel {self.name!r}: uniform={self.uniform!r} names no argument {unknown}")
        return params, ret

    def __repr__(self):
        return f"<kernel {self.name}>"


def kernel(fn=None, *, uniform=()):
    """Record ``fn`` as a CGA kernel. ``uniform``: names of the inputs the batch form takes once
    (a single value for every row) instead of one per row."""
    if fn is None:
        return lambda f: KernelSpec(f, uniform)
    return KernelSpec(fn, uniform)
