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
the types and constants above as attributes. The values and their operators are in ``values.py``.
Importing this module does not import sympy.
"""
from __future__ import annotations

import functools
import inspect
import typing

from . import algebras
from .layouts import MOTOR, PLANE, ROTOR, VERSOR
from .values import Constant, Value, _apply, _error, _functions, _ring


class Type:
    """A blade set of ``algebra``: inputs of this type are (len(blades),) arrays of coefficients in that
    order. ``space`` is the name the algebra goes by in kernels (``cga``, ``pga``)."""

    kind = "multivector"

    def __init__(self, name: str, blades, versor: bool = False, algebra=algebras.cga, space="cga"):
        self.name, self.algebra, self.space = name, algebra, space
        self.versor = versor          # values are versors: V Ṽ is a scalar, V e Ṽ a vector
        self.blades = tuple(algebra.blade_name(algebra.mask_of(b)) for b in blades)
        if len(set(self.blades)) != len(self.blades):
            raise algebras.InvalidAlgebraError(f"{name}: a blade is repeated in {self.blades}")

    @property
    def size(self) -> int:
        return len(self.blades)

    def _shown(self, blades) -> str:
        return ", ".join(self.algebra.blade_display(self.algebra.mask_of(b)) for b in blades)

    def describe(self) -> str:
        return f"{self.name} ({self._shown(self.blades)})"

    def declare(self, k, arg: str):
        """Declare the input ``arg`` on ``ir.KernelBuilder`` k; returns its symbols."""
        return k.multivector(arg, self.blades)

    def value(self, k, symbols) -> Value:
        return Value(k.mv(self.blades, symbols, self.algebra))

    def _check(self, kernel: str, mv, allowed):
        if set(mv.terms) - {0} and mv.algebra != self.algebra:
            raise _error(f"kernel {kernel!r}: the result is a value of {mv.algebra}, its return type "
                         f"{self!r} is of {self.algebra}")
        masks = {self.algebra.mask_of(b) for b in allowed}
        extra = [m for m in mv.blades if m not in masks]
        if extra:
            names = ", ".join(self.algebra.blade_display(m) for m in extra)
            raise _error(f"kernel {kernel!r}: the result has blades {names} outside its return type "
                         f"{self.describe()}")

    def outputs(self, kernel: str, mv):
        """(labels, numerator polynomials, denominator polynomial or None) of a result of this type."""
        self._check(kernel, mv, self.blades)
        return ([self.algebra.blade_display(self.algebra.mask_of(b)) for b in self.blades],
                _functions().final(_ring(), [mv[b] for b in self.blades]), None)

    def __repr__(self):
        return f"{self.space}.{self.name}"


class ScalarType(Type):
    kind = "scalar"

    def declare(self, k, arg):
        return (k.scalar(arg),)


class PointType(Type):
    """A point passed as its Euclidean (3,) coordinates x. The algebra sees Σ_b coordinate_b · b over
    ``embedding`` {blade: (sign, axis or None)} (None: the weight blade, coefficient 1; a blade named
    ``"norm"`` instead of an axis gets ½|x|², as CGA's e∞); a result is down-projected to
    x_axis = sign · coefficient / weight."""

    kind = "point"

    def __init__(self, embedding: dict, algebra=algebras.cga, space="cga"):
        self.embedding = embedding
        super().__init__("Point", tuple(embedding), algebra=algebra, space=space)

    @property
    def size(self) -> int:
        return 3

    def describe(self) -> str:
        return f"Point ({self._shown(self.blades)}: up-projected from / down-projected to (3,))"

    def declare(self, k, arg):
        return k.array(arg, 3)

    def value(self, k, symbols):
        from sympy import QQ
        x = [k.poly(s) for s in symbols]
        coefficients = [k.ring.one if axis is None else
                        (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) * QQ(sign, 2) if axis == "norm" else x[axis] * sign
                        for sign, axis in self.embedding.values()]
        return Value(k.mv(self.blades, coefficients, self.algebra))

    def outputs(self, kernel, mv):
        self._check(kernel, mv, self.blades)
        axes = {axis: (blade, sign) for blade, (sign, axis) in self.embedding.items() if axis not in ("norm", None)}
        weight_blade = next(b for b, (_, axis) in self.embedding.items() if axis is None)
        weight = mv[weight_blade]
        if not weight:
            raise _error(f"kernel {kernel!r}: the result has no {self._shown([weight_blade])} part, so it is not "
                         f"a point to down-project")
        *nums, weight = _functions().final(_ring(), [mv[axes[i][0]] * axes[i][1] for i in range(3)] + [weight])
        return ["x[0]", "x[1]", "x[2]"], nums, weight


class _MultivectorFactory:
    """``cga.Multivector["e1", "e2", "ei"]``: the type of any blade set, in the order given."""

    def __init__(self, algebra, space):
        self.algebra, self.space = algebra, space

    def __getitem__(self, blades):
        blades = (blades,) if isinstance(blades, str) else tuple(blades)
        shown = ", ".join(self.algebra.blade_display(self.algebra.mask_of(b)) for b in blades)
        return Type(f"Multivector[{shown}]", blades, algebra=self.algebra, space=self.space)

    def __repr__(self):
        return f"{self.space}.Multivector"


class KernelAlgebra(algebras.Algebra):
    """An ``Algebra`` with the language's types, constants and scalar functions as attributes; equal to
    the plain algebra ``base`` and sharing its tables. Subclasses declare the types."""

    sqrt, cos, sin, exp, log, abs, atan2, where = (staticmethod(functools.partial(_apply, n)) for n in
                                                   ("sqrt", "cos", "sin", "exp", "log", "abs", "atan2", "where"))

    def __init__(self, base: algebras.Algebra, space: str):
        super().__init__(signature=base.signature, basis=base.basis)
        self._tables = base._tables
        self.space = space
        self.Multivector = _MultivectorFactory(base, space)


class ConformalAlgebra(KernelAlgebra):
    """G(4,1) in the null basis (equal to ``codegen.algebras.cga``) with the kernel language's types.

    ``cgaskin.codegen.cga`` is its one instance: the types kernels annotate their inputs with
    (Scalar, Vector, Point, Plane, Sphere, Line, Rotor, Motor, Versor, ``Multivector[...]``), the
    constants e1, e2, e3, einf, eo and the scalar functions (``sqrt``, ``cos``, ..., ``where``).

    Examples
    --------
    >>> from cgaskin.codegen import cga
    >>> print(cga.Motor.describe())
    Motor (1, e12, e13, e23, e1∞, e2∞, e3∞, e123∞)
    >>> cga.Point.size, str(cga)
    (3, 'G(4,1,0), null basis e1 e2 e3 e∞ e0')
    """

    Scalar = ScalarType("Scalar", ("s",))
    Vector = Type("Vector", ("e1", "e2", "e3"))
    Point = PointType({"e1": (1, 0), "e2": (1, 1), "e3": (1, 2), "ei": (1, "norm"), "eo": (1, None)})
    Plane = Type("Plane", PLANE)
    Sphere = Type("Sphere", ("e1", "e2", "e3", "ei", "eo"))
    Line = Type("Line", ("e12", "e13", "e23", "e1i", "e2i", "e3i"))
    Rotor = Type("Rotor", ROTOR, versor=True)
    Motor = Type("Motor", MOTOR, versor=True)
    Versor = Type("Versor", VERSOR, versor=True)
    e1, e2, e3, einf, eo = (Constant(n) for n in ("e1", "e2", "e3", "ei", "eo"))

    def __init__(self):
        super().__init__(algebras.cga, "cga")


cga = ConformalAlgebra()


class KernelSpec:
    """A kernel recorded by ``@kernel``: the function, its name, docstring and uniform inputs.

    Calling it calls the function (so kernels can use each other while traced).

    Parameters
    ----------
    fn : callable
        The kernel: a function of typed multivectors (``cga.Point``, ...) returning one.
    uniform : str or sequence of str, optional
        The inputs its batch form takes once (one value for every row).

    Examples
    --------
    >>> from cgaskin.codegen import cga, kernel
    >>> @kernel(uniform=("V",))
    ... def move(V: cga.Versor, x: cga.Point) -> cga.Point:
    ...     return V * x * ~V
    >>> move.name, move.uniform
    ('move', ('V',))
    """

    def __init__(self, fn, uniform=()):
        self.fn = fn
        self.name = fn.__name__
        self.doc = inspect.getdoc(fn) or ""
        self.uniform = (uniform,) if isinstance(uniform, str) else tuple(uniform)
        functools.update_wrapper(self, fn)

    def __call__(self, *args, **kwargs):
        return self.fn(*args, **kwargs)

    def signature(self):
        """The kernel's argument types and return type, from its annotations (strings are resolved).

        Returns
        -------
        params : list of (str, Type)
            Each argument's name and type, in order.
        result : Type
            The return type.

        Raises
        ------
        CodegenError
            An argument or the return without a ``cga``/``pga`` type, or ``uniform`` naming no argument.
        """
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
    """Record a function as a kernel of the language: what ``cgaskin build --catalogue`` compiles.

    Parameters
    ----------
    fn : callable, optional
        The kernel, its inputs and return annotated with types of ``cga`` (or ``pga``); omitted
        when ``@kernel(uniform=...)`` is used with arguments.
    uniform : str or sequence of str, optional
        The inputs the batch form takes once (a single value for every row) instead of one per row.

    Returns
    -------
    KernelSpec or callable
        The recorded kernel (with ``fn``), else a decorator that records one.

    Examples
    --------
    >>> from cgaskin.codegen import cga, kernel
    >>> @kernel
    ... def reflect(plane: cga.Plane, x: cga.Point) -> cga.Point:
    ...     return -plane * x * plane
    >>> reflect.signature()
    ([('plane', cga.Plane), ('x', cga.Point)], cga.Point)
    """
    if fn is None:
        return lambda f: KernelSpec(f, uniform)
    return KernelSpec(fn, uniform)
