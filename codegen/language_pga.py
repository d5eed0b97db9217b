"""The kernel language in projective geometric algebra: ``pga``, G(3,0,1) with the types of klein and
bivector.net (e0 e1 e2 e3, e0² = 0; a plane is a vector, a point a trivector).

    from cgaskin.codegen import kernel, pga

    @kernel(uniform=("M",))
    def move(M: pga.Motor, x: pga.Point) -> pga.Point:
        return M * x * ~M

Types (attributes of ``pga``; blades of ``codegen.algebras.pga``, canonical names in index order):
    Scalar      float
    Plane       (a, b, c, d) = a e1 + b e2 + c e3 + d e0: the plane {x : a x + b y + c z + d = 0}
    Point       Euclidean (3,) array, up-projected to x e032 + y e013 + z e021 + e123 (stored on the
                canonical blades e023 = −e032, e013, e012 = −e021, e123), down-projected on return
                (over the e123 coefficient)
    Line        (e01, e02, e03, e12, e13, e23)
    Rotor       (s, e12, e13, e23)      Translator  (s, e01, e02, e03)
    Motor       (s, e01, e02, e03, e12, e13, e23, e0123)
    Multivector["e0", "e12", ...]  any blade set, in the order given
Conventions (checked against plain matrices in tests/codegen/test_pga.py): the rotor
cos(θ/2) − sin(θ/2)(n1 e23 − n2 e13 + n3 e12) turns by θ about the unit axis n (right-handed, as CGA's
in design.md §2), the translator 1 − ½(t1 e01 + t2 e02 + t3 e03) moves x to x + t, and a motor T R
applies R first; M x M̃ moves a point, −p x p reflects it in the plane p.
Constants ``pga.e0 … pga.e3``; the operators and scalar functions are the same as ``cga``'s
(``codegen.language``). ``.dual()`` is refused: the pseudoscalar of a degenerate metric squares to 0.
"""
from __future__ import annotations

from . import algebras
from .language import KernelAlgebra, PointType, ScalarType, Type
from .values import Constant

_PGA = dict(algebra=algebras.pga, space="pga")
_MOTOR = ("s", "e01", "e02", "e03", "e12", "e13", "e23", "e0123")


class ProjectiveAlgebra(KernelAlgebra):
    """G(3,0,1) (equal to ``codegen.algebras.pga``) with the kernel language's types.

    ``cgaskin.codegen.pga`` is its one instance: Scalar, Plane, Point, Line, Rotor, Translator, Motor,
    ``Multivector[...]`` and the constants e0 ... e3.

    Examples
    --------
    >>> from cgaskin.codegen import kernel, pga
    >>> @kernel(uniform=("M",))
    ... def move(M: pga.Motor, x: pga.Point) -> pga.Point:
    ...     return M * x * ~M
    >>> print(pga.Motor.describe())
    Motor (1, e01, e02, e03, e12, e13, e23, e0123)
    """

    Scalar = ScalarType("Scalar", ("s",), **_PGA)
    Plane = Type("Plane", ("e1", "e2", "e3", "e0"), **_PGA)
    Point = PointType({"e023": (-1, 0), "e013": (1, 1), "e012": (-1, 2), "e123": (1, None)}, **_PGA)
    Line = Type("Line", ("e01", "e02", "e03", "e12", "e13", "e23"), **_PGA)
    Rotor = Type("Rotor", ("s", "e12", "e13", "e23"), versor=True, **_PGA)
    Translator = Type("Translator", ("s", "e01", "e02", "e03"), versor=True, **_PGA)
    Motor = Type("Motor", _MOTOR, versor=True, **_PGA)
    e0, e1, e2, e3 = (Constant(n, **_PGA) for n in ("e0", "e1", "e2", "e3"))

    def __init__(self):
        super().__init__(algebras.pga, "pga")


pga = ProjectiveAlgebra()
