"""Geometry kernels that need named intermediates (coordinates relative to a vertex, the idempotent
split): planes through points or moved by a versor, segment-plane meets, point-line distances,
barycentric coordinates. The plane from a normal and the point-plane distance are written in the
language (``kernels_language``)."""
from __future__ import annotations

from sympy import sqrt

from . import algebra
from .ir import CodegenError, KernelBuilder
from .kernel_parts import euclid, idempotent_versor
from .layouts import PLANE, VERSOR
from .symbolic import MV, up


def _relative(k, name: str, point, origin) -> tuple:
    """Intermediates name0..name2 = point − origin: products of them stay in relative coordinates
    (expanding point − origin into the products would bring back absolute ones: error ~ε|origin|²)."""
    syms = k.intermediate(*(f"{name}{i}" for i in range(3)))
    for s_, pi, oi in zip(syms, point, origin):
        k.let(s_, pi - oi)
    return syms


def plane_from_points():
    k = KernelBuilder("plane_from_points",
                      "Dual plane through a, b, c (normal along (b−a)×(c−a)), computed relative to a for "
                      "accuracy far from the origin: π' = −(e0 ∧ up(b−a) ∧ up(c−a) ∧ e∞)*, then "
                      "normalised and moved back by d = n̂·a.")
    a, b, c = k.array("a", 3), k.array("b", 3), k.array("c", 3)
    u, w = _relative(k, "u", b, a), _relative(k, "w", c, a)        # the edge vectors
    n1, n2, n3, inv = k.intermediate("n1", "n2", "n3", "inv_len")
    o = MV(k.ring, {algebra.mask_of("eo"): k.ring.one})
    inf = MV(k.ring, {algebra.mask_of("ei"): k.ring.one})
    U = up(k.ring, [k.poly(e) for e in u])
    W = up(k.ring, [k.poly(e) for e in w])
    P = -((o ^ U ^ W ^ inf).dual())
    if P["ei"] != 0:
        raise CodegenError("plane through the origin must have no e∞ part")
    for sym, e in zip((n1, n2, n3), euclid(k, P)):
        k.let(sym, e)
    k.let(inv, 1 / sqrt(n1 ** 2 + n2 ** 2 + n3 ** 2))
    k.output(["plane[e1]", "plane[e2]", "plane[e3]", "plane[e∞]"],
             [n1 * inv, n2 * inv, n3 * inv, (n1 * a[0] + n2 * a[1] + n3 * a[2]) * inv])
    return k.build()


def plane_transform():
    k = KernelBuilder("plane_transform", "The plane moved by a versor: V π Ṽ, renormalised to a unit normal.")
    v, p = k.multivector("v", VERSOR), k.multivector("plane", PLANE)
    inv = k.intermediate("inv_len")[0]
    V = idempotent_versor(k, v)
    moved = V * k.mv(PLANE, p) * V.reverse()
    n = euclid(k, moved)
    k.let(inv, 1 / sqrt(sum(c.as_expr() ** 2 for c in n)))
    k.output_multivector("plane", moved.grade(1), PLANE, scale=inv)
    return k.build()


def segment_plane():
    k = KernelBuilder("segment_plane",
                      "Where segment a→b meets plane π: t = d_a / (d_a − d_b) with d the signed distances "
                      "up(·)·π, and the point a + t (b − a). t is outside [0, 1] when the segment misses.")
    p, a, b = k.multivector("plane", PLANE), k.array("a", 3), k.array("b", 3)
    P = k.mv(PLANE, p)
    da, db, t = k.intermediate("da", "db", "t")
    k.let(da, up(k.ring, [k.poly(c) for c in a]).lc(P)["s"])
    k.let(db, up(k.ring, [k.poly(c) for c in b]).lc(P)["s"])
    k.let(t, da / (da - db))
    k.output(["t", "x[0]", "x[1]", "x[2]"], [t] + [ai + t * (bi - ai) for ai, bi in zip(a, b)])
    return k.build()


def point_line_distance():
    # Not in the kernel language: it expands x − a into the products (x_i u_j − a_i u_j ...), so the
    # square of the bivector would cancel terms ~|a|²|u|² (error ~ε|a|²/d where d is the distance).
    # Here x − a and the bivector's three coefficients are intermediates: each coefficient carries
    # ~ε|x − a||u| as np.cross does, whatever the distance from the origin.
    k = KernelBuilder("point_line_distance",
                      "Distance |(x − a) ∧ u| / |u| of the point x from the line through a with direction u "
                      "(u need not be unit), relative to a: with q = x − a and B = q ∧ u, "
                      "d = sqrt(⟨B B̃⟩₀ / u·u). NaN for u = 0.")
    a, u, x = k.array("a", 3), k.array("u", 3), k.array("x", 3)
    q = _relative(k, "q", x, a)
    b = k.intermediate("b12", "b13", "b23")
    vec = lambda syms: k.mv(("e1", "e2", "e3"), syms)  # noqa: E731
    U = vec(u)
    B = vec(q) ^ U
    for s_, blade in zip(b, ("e12", "e13", "e23")):
        k.let(s_, B[blade].as_expr())
    Bn = k.mv(("e12", "e13", "e23"), b)
    k.output(["d"], [sqrt((Bn * Bn.reverse())["s"].as_expr() / (U * U)["s"].as_expr())])
    return k.build()


def barycentric():
    k = KernelBuilder("barycentric",
                      "Barycentric coordinates (λa, λb, λc) of p projected on triangle abc, relative to a: "
                      "with u = b−a, w = c−a, q = p−a: λb = (q∧w)·(u∧w)~/|u∧w|², λc = (u∧q)·(u∧w)~/|u∧w|².")
    a, b, c, pt = (k.array(n, 3) for n in ("a", "b", "c", "p"))
    ub, wb, qb = _relative(k, "u", b, a), _relative(k, "w", c, a), _relative(k, "q", pt, a)
    vec = lambda syms: k.mv(("e1", "e2", "e3"), syms)  # noqa: E731
    U, W, Q = vec(ub), vec(wb), vec(qb)
    area = U ^ W
    area_rev = area.reverse()
    inv = k.intermediate("inv_area2")[0]
    k.let(inv, 1 / (area * area_rev)["s"].as_expr())
    lb = ((Q ^ W) * area_rev)["s"].as_expr() * inv
    lc = ((U ^ Q) * area_rev)["s"].as_expr() * inv
    k.output(["λa", "λb", "λc"], [1 - lb - lc, lb, lc])
    return k.build()
