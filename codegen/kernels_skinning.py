"""Point kernels: the direct sandwich, and its hoisted per-bone affine form that skinning uses."""
from __future__ import annotations

from .ir import CodegenError, KernelBuilder
from .kernel_parts import down, euclid, idempotent_versor
from .layouts import AFFINE_LABELS, VERSOR
from .symbolic import up


def _sandwich_point(k, v, x):
    V = idempotent_versor(k, v)
    return V * up(k.ring, [k.poly(c) for c in x]) * V.reverse()


def sandwich_versor_point():
    k = KernelBuilder("sandwich_versor_point",
                      "down(V up(x) Ṽ): the full sandwich on one point (use versor_to_affine for many).")
    v, x = k.multivector("v", VERSOR), k.array("x", 3)
    k.output(["x'[0]", "x'[1]", "x'[2]"], down(k, _sandwich_point(k, v, x)))
    return k.build()


def hoist_affine(k, X, x_syms):
    """Split down(X) with X polynomial in the per-vertex symbols x into a per-bone affine map.

    Returns (A (3x4 expressions), weight): down(X) = A[:, :3] x + A[:, 3]. Raises CodegenError when
    the e0 weight depends on x or the Euclidean part is not affine in x (then no exact hoist exists).
    """
    ring = k.ring
    idx = [ring.symbols.index(s) for s in x_syms]
    weight = X["eo"]
    if any(any(mon[i] for i in idx) for mon in weight.monoms()):
        raise CodegenError(f"{k.name}: the point weight depends on the point; cannot hoist")
    rows = []
    for c in euclid(k, X):
        by_degree: dict[int, object] = {}
        for mon, coef in c.terms():
            degrees = [mon[i] for i in idx]
            if sum(degrees) > 1:
                raise CodegenError(f"{k.name}: the sandwich is not affine in the point; cannot hoist")
            col = degrees.index(1) if sum(degrees) else 3
            stripped = tuple(0 if i in idx else e for i, e in enumerate(mon))
            by_degree[col] = by_degree.get(col, ring.zero) + ring({stripped: coef})
        rows.append([by_degree.get(col, ring.zero) for col in range(4)])
    return rows, weight


def versor_to_affine():
    k = KernelBuilder("versor_to_affine",
                      "The hoisted form of the point sandwich: down(V up(x) Ṽ) = A[:, :3] x + A[:, 3] "
                      "for every x, found by collecting V up(x) Ṽ by powers of x (the e0 weight and the "
                      "x² terms drop out of the Euclidean part). Returns A (3, 4) row-major.")
    v, x = k.multivector("v", VERSOR), k.array("x", 3)
    rows, weight = hoist_affine(k, _sandwich_point(k, v, x), x)
    k.eliminate("x")
    inv_w = k.intermediate("inv_w")[0]
    k.let(inv_w, 1 / weight.as_expr())
    k.output(AFFINE_LABELS, [e.as_expr() * inv_w for row in rows for e in row], shape=(3, 4))
    return k.build()


def affine_point():
    k = KernelBuilder("affine_point", "The per-vertex half of the hoist: A[:, :3] x + A[:, 3]; A (12,) row-major.")
    a, x = k.array("a", 12), k.array("x", 3)
    k.output(["x'[0]", "x'[1]", "x'[2]"],
             [a[4 * r] * x[0] + a[4 * r + 1] * x[1] + a[4 * r + 2] * x[2] + a[4 * r + 3] for r in range(3)])
    return k.build()
