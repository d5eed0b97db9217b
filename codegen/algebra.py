"""The conformal algebra G(4,1) in the null basis (e1, e2, e3, e∞, e0), as numeric product tables.

This module is the home of the one algebra every kernel is written in: ``cga``, the instance
``Algebra(signature=(4, 1, 0), basis="null")`` of ``codegen.algebras`` (which builds any G(p, q, r) up to
6 dimensions). Its names below are thin aliases onto ``cga``, kept for the modules that say
``algebra.mask_of(...)``, ``algebra.product_table(...)``.

Blades are bitmasks over the basis vectors in that order (bit 0 = e1 ... bit 3 = e∞, bit 4 = e0); the
blade of mask m is the *outer* product of its vectors in index order (e∞0 = e∞∧e0, not e∞e0).

The metric is diagonal only in the orthonormal basis (e1, e2, e3, e+, e−) with e+² = 1, e−² = −1.
There, the product of two basis blades is one basis blade with a sign; so every table here is made by
expanding null blades into orthonormal ones, multiplying there, and expanding back:
    e∞ = e− + e+,   e0 = (e− − e+)/2,   e+ = e∞/2 − e0,   e− = e∞/2 + e0.
All coefficients are exact fractions.
"""
from __future__ import annotations

from .algebras import Algebra, cga, grade, reorder_sign, reverse_sign

__all__ = ["Algebra", "cga", "DIMENSION", "N_BLADES", "VECTOR_NAMES", "DISPLAY_NAMES", "ORTHONORMAL_METRIC",
           "NULL_TO_ORTHO", "ORTHO_TO_NULL", "PSEUDOSCALAR", "grade", "vectors_of", "blade_name",
           "blade_display", "mask_of", "reorder_sign", "product_table", "reverse_sign"]

DIMENSION = cga.dimension                           # 5
N_BLADES = cga.n_blades                             # 32
VECTOR_NAMES = cga.vector_names                     # ("1", "2", "3", "i", "o"): identifier-safe, i = ∞, o = 0
DISPLAY_NAMES = cga.display_names                   # ("1", "2", "3", "∞", "0")
ORTHONORMAL_METRIC = cga.orthonormal_metric         # (1, 1, 1, 1, -1): e1, e2, e3, e+, e−

# null vector k -> {orthonormal vector index: coefficient}, and back
NULL_TO_ORTHO = cga.to_orthonormal
ORTHO_TO_NULL = cga.from_orthonormal

vectors_of = cga.vectors_of
blade_name = cga.blade_name
blade_display = cga.blade_display
mask_of = cga.mask_of
product_table = cga.product_table

PSEUDOSCALAR = cga.pseudoscalar                     # e123∞0 = e1 e2 e3 e+ e−
