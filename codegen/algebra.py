"""The conformal algebra G(4,1) in the null basis (e1, e2, e3, e∞, e0), as numeric product tables.

Blades are bitmasks over the basis vectors in that order (bit 0 = e1 ... bit 3 = e∞, bit 4 = e0); the
blade of mask m is the *outer* product of its vectors in index order (e∞0 = e∞∧e0, not e∞e0).

The metric is diagonal only in the orthonormal basis (e1, e2, e3, e+, e−) with e+² = 1, e−² = −1.
There, the product of two basis blades is one basis blade with a sign; so every table here is made by
expanding null blades into orthonormal ones, multiplying there, and expanding back:
    e∞ = e− + e+,   e0 = (e− − e+)/2,   e+ = e∞/2 − e0,   e− = e∞/2 + e0.
All coefficients are exact fractions.
"""
from __future__ import annotations

from fractions import Fraction
from functools import lru_cache

DIMENSION = 5
N_BLADES = 1 << DIMENSION
VECTOR_NAMES = ("1", "2", "3", "i", "o")          # identifier-safe: i = ∞, o = 0
DISPLAY_NAMES = ("1", "2", "3", "∞", "0")
ORTHONORMAL_METRIC = (1, 1, 1, 1, -1)              # e1, e2, e3, e+, e−

# null vector k -> {orthonormal vector index: coefficient}, and back
NULL_TO_ORTHO = ({0: 1}, {1: 1}, {2: 1}, {4: 1, 3: 1}, {4: Fraction(1, 2), 3: Fraction(-1, 2)})
ORTHO_TO_NULL = ({0: 1}, {1: 1}, {2: 1}, {3: Fraction(1, 2), 4: -1}, {3: Fraction(1, 2), 4: 1})


def grade(mask: int) -> int:
    return bin(mask).count("1")


def vectors_of(mask: int) -> tuple[int, ...]:
    return tuple(k for k in range(DIMENSION) if mask >> k & 1)


def blade_name(mask: int) -> str:
    """Identifier-safe name: 's' for the scalar, else e.g. 'e12i' for e1∧e2∧e∞."""
    return "s" if mask == 0 else "e" + "".join(VECTOR_NAMES[k] for k in vectors_of(mask))


def blade_display(mask: int) -> str:
    """Readable name for docstrings: '1', 'e12∞', 'e∞0'."""
    return "1" if mask == 0 else "e" + "".join(DISPLAY_NAMES[k] for k in vectors_of(mask))


def mask_of(name: str) -> int:
    """Inverse of ``blade_name`` (also accepts the display names)."""
    if name in ("s", "1"):
        return 0
    mask = 0
    for ch in name[1:]:
        k = VECTOR_NAMES.index(ch) if ch in VECTOR_NAMES else DISPLAY_NAMES.index(ch)
        mask |= 1 << k
    return mask


def reorder_sign(a: int, b: int) -> int:
    """Sign of moving the vectors of blade b past those of blade a into index order."""
    swaps = 0
    a >>= 1
    while a:
        swaps += grade(a & b)
        a >>= 1
    return -1 if swaps & 1 else 1


def _wedge_expand(vectors: tuple[int, ...], change: tuple[dict, ...]) -> dict[int, Fraction]:
    """Outer product of basis vectors rewritten in another basis: {mask: coefficient}."""
    terms = {0: Fraction(1)}
    for v in vectors:
        nxt: dict[int, Fraction] = {}
        for mask, coef in terms.items():
            for w, c in change[v].items():
                bit = 1 << w
                if mask & bit:
                    continue                      # repeated vector: the wedge vanishes
                key = mask | bit
                nxt[key] = nxt.get(key, 0) + coef * c * reorder_sign(mask, bit)
        terms = {k: c for k, c in nxt.items() if c}
    return terms


def _ortho_product(a: int, b: int, kind: str) -> tuple[int, int] | None:
    """Product of two orthonormal basis blades: (mask, sign) or None when it vanishes."""
    if kind == "outer" and a & b:
        return None
    if kind == "lcontract" and a & b != a:
        return None
    sign = reorder_sign(a, b)
    for k in vectors_of(a & b):
        sign *= ORTHONORMAL_METRIC[k]
    return a ^ b, sign


@lru_cache(maxsize=None)
def product_table(kind: str) -> dict[tuple[int, int], tuple[tuple[int, Fraction], ...]]:
    """{(mask_a, mask_b): ((mask, coefficient), ...)} for kind in 'gp', 'outer', 'lcontract'."""
    to_ortho = [_wedge_expand(vectors_of(m), NULL_TO_ORTHO) for m in range(N_BLADES)]
    to_null = [_wedge_expand(vectors_of(m), ORTHO_TO_NULL) for m in range(N_BLADES)]
    table = {}
    for a in range(N_BLADES):
        for b in range(N_BLADES):
            ortho: dict[int, Fraction] = {}
            for oa, ca in to_ortho[a].items():
                for ob, cb in to_ortho[b].items():
                    hit = _ortho_product(oa, ob, kind)
                    if hit:
                        ortho[hit[0]] = ortho.get(hit[0], 0) + ca * cb * hit[1]
            null: dict[int, Fraction] = {}
            for om, c in ortho.items():
                for nm, cn in to_null[om].items():
                    null[nm] = null.get(nm, 0) + c * cn
            table[a, b] = tuple(sorted((m, Fraction(c)) for m, c in null.items() if c))
    return table


def reverse_sign(mask: int) -> int:
    g = grade(mask)
    return -1 if (g * (g - 1) // 2) & 1 else 1


PSEUDOSCALAR = N_BLADES - 1                        # e123∞0 = e1 e2 e3 e+ e−
