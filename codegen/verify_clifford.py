"""The clifford side of ``cgaskin verify``: the language's values wrapping ``clifford`` multivectors.

Any ``codegen.algebras.Algebra`` G(p,q,r) is ``clifford.Cl(p, q, r)`` (the same order of orthonormal
vectors: degenerate, positive, negative); our basis vector k is Σ_j to_orthonormal[k][j] · clifford's
e(j+1) (for CGA: e∞ = e− + e+, e0 = ½(e− − e+)), our blade of mask m the outer product of its vectors.
``|`` is the left contraction ``<<``, ``.dual()`` is X I⁻¹ with I our pseudoscalar, and scalar
functions are evaluated in floats.
"""
from __future__ import annotations

import clifford
import numpy as np

from . import algebras
from .functions import NUMERIC, OPERATORS
from .values import Value



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
        return CliffordMV(self.x * _BACKENDS[id(self.x.layout)].I_inv)


class CliffordBackend:
    """The clifford layout of an algebra, our blades in it, and the change of coefficients."""

    def __init__(self, alg: algebras.Algebra):
        self.algebra = alg
        p, q, r = alg.signature
        self.layout, blades = clifford.Cl(p, q, r)
        ortho = [blades[f"e{j + 1}"] for j in range(alg.dimension)]
        vectors = [sum((float(c) * ortho[j] for j, c in alg.to_orthonormal[k].items()), 0 * ortho[0])
                   for k in range(alg.dimension)]
        self.one = self.layout.scalar
        self.blades = []
        for mask in range(alg.n_blades):
            blade = self.one
            for k in alg.vectors_of(mask):
                blade = blade ^ vectors[k]
            self.blades.append(blade)
        self.to_ours = np.linalg.inv(np.array([bl.value for bl in self.blades]).T)
        top = self.blades[alg.pseudoscalar]
        self.I_inv = top.inv() if (top * top).value[0] else None

    # the "ring" protocol of values._scalar_mv / Constant.mv
    def scalar_mv(self, q):
        return CliffordMV(float(q) * self.one)

    def basis_mv(self, name: str, alg=None):
        return CliffordMV(self.blades[self.algebra.mask_of(name)])

    def function(self, name, *args):           # values._apply: scalar functions, conditions, where
        if name == "where":
            return args[1] if args[0] else args[2]
        xs = [float(a.x.value[0]) for a in args]
        return OPERATORS[name](*xs) if name in OPERATORS else CliffordMV(NUMERIC[name](*xs) * self.one)

    def _on(self, blades, coefficients):
        return CliffordMV(sum((float(c) * self.blades[self.algebra.mask_of(n)] for n, c in zip(blades, coefficients)),
                              0 * self.one))

    def value(self, typ, arr) -> Value:
        if typ.kind == "scalar":
            return Value(CliffordMV(float(arr) * self.one))
        if typ.kind == "point":                 # up-projection (language.PointType's embedding)
            x = np.asarray(arr, float)
            coefficients = [1.0 if axis is None else 0.5 * sign * float(x @ x) if axis == "norm" else sign * x[axis]
                            for sign, axis in typ.embedding.values()]
            return Value(self._on(typ.blades, coefficients))
        return Value(self._on(typ.blades, arr))

    def coefficients(self, mv) -> np.ndarray:
        return self.to_ours @ mv.x.value

    def result(self, typ, mv) -> np.ndarray:
        c = self.coefficients(mv)
        if typ.kind == "point":                 # down-projection: sign · coefficient / weight per axis
            by_axis = {axis: (self.algebra.mask_of(b), sign) for b, (sign, axis) in typ.embedding.items()}
            weight = c[by_axis[None][0]]
            return np.array([by_axis[i][1] * c[by_axis[i][0]] / weight for i in range(3)])
        return c[[self.algebra.mask_of(n) for n in typ.blades]]


_BACKENDS: dict = {}                           # id(clifford layout) -> its backend (for dual)


def backend(alg: algebras.Algebra = algebras.cga) -> CliffordBackend:
    """The (cached) clifford backend of ``alg``."""
    for be in _BACKENDS.values():
        if be.algebra == alg:
            return be
    be = CliffordBackend(alg)
    _BACKENDS[id(be.layout)] = be
    return be
