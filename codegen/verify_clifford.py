"""The clifford side of ``cgaskin verify``: the language's values wrapping ``clifford`` multivectors.

G(4,1) of ``clifford.conformalize(Cl(3))``, with e∞ = e− + e+ and e0 = ½(e− − e+) as in
``codegen.algebras.cga``; ``|`` is the left contraction ``<<``, ``.dual()`` is X I⁻¹ with
I = e1∧e2∧e3∧e∞∧e0, and scalar functions are evaluated in floats.
"""
from __future__ import annotations

import clifford
import numpy as np

from . import algebras
from .functions import NUMERIC, OPERATORS
from .values import Value

_CGA = algebras.cga


class CliffordMV:
    """A clifford MultiVector with ``symbolic.MV``'s interface, so ``values.Value`` can wrap it."""

    __slots__ = ("x",)

    def __init__(self, x):
        self.x = x

    def __mul__(self, o):
        return CliffordMV(self.x * o.x)

    def __xor__(self, o):
        return CliffordMV(self.x ^ o.x)

    def lc(self, o):
        return CliffordMV(self.x << o.x)

    def __add__(self, o):
        return CliffordMV(self.x + o.x)

    def __sub__(self, o):
        return CliffordMV(self.x - o.x)

    def __neg__(self):
        return CliffordMV(-self.x)

    def reverse(self):
        return CliffordMV(~self.x)

    def grade(self, *grades):
        return CliffordMV(sum((self.x(g) for g in grades), 0 * self.x))

    def dual(self):
        return CliffordMV(self.x * _backend().I_inv)


class CliffordBackend:
    """The conformal layout of clifford, our null-basis blades in it, and the coefficient change."""

    def __init__(self):
        layout, _, stuff = clifford.conformalize(clifford.Cl(3)[0])
        self.layout = layout
        b = layout.blades
        vectors = [b["e1"], b["e2"], b["e3"], stuff["einf"], stuff["eo"]]   # bit order of algebras.cga
        self.one = layout.scalar
        self.blades = []
        for mask in range(32):
            blade = self.one
            for k in range(5):
                if mask >> k & 1:
                    blade = blade ^ vectors[k]
            self.blades.append(blade)
        self.to_ours = np.linalg.inv(np.array([bl.value for bl in self.blades]).T)
        self.I_inv = self.blades[31].inv()

    # the "ring" protocol of values._scalar_mv / Constant.mv
    def scalar_mv(self, q):
        return CliffordMV(float(q) * self.one)

    def basis_mv(self, name: str):
        return CliffordMV(self.blades[_CGA.mask_of(name)])

    def function(self, name, *args):           # values._apply: scalar functions, conditions, where
        if name == "where":
            return args[1] if args[0] else args[2]
        xs = [float(a.x.value[0]) for a in args]
        return OPERATORS[name](*xs) if name in OPERATORS else CliffordMV(NUMERIC[name](*xs) * self.one)

    def value(self, typ, arr) -> Value:
        if typ.kind == "scalar":
            return Value(CliffordMV(float(arr) * self.one))
        if typ.kind == "point":
            x = np.asarray(arr, float)
            mv = sum(x[i] * self.blades[1 << i] for i in range(3)) + 0.5 * float(x @ x) * self.blades[8] + self.blades[16]
            return Value(CliffordMV(mv))
        return Value(CliffordMV(sum((float(c) * self.blades[_CGA.mask_of(n)] for n, c in zip(typ.blades, arr)),
                                    0 * self.one)))

    def coefficients(self, mv) -> np.ndarray:
        return self.to_ours @ mv.x.value

    def result(self, typ, mv) -> np.ndarray:
        c = self.coefficients(mv)
        if typ.kind == "point":
            return c[[1, 2, 4]] / c[16]
        return c[[_CGA.mask_of(n) for n in typ.blades]]


_BACKEND: list = []


def _backend() -> CliffordBackend:
    if not _BACKEND:
        _BACKEND.append(CliffordBackend())
    return _BACKEND[0]
