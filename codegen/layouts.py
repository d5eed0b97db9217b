"""The array layouts of the built-in kernels: which blade each coefficient of an array holds.

Declared once, here: the builder kernels (``kernel_parts``), the kernel language's types
(``language``), ``verify`` and generated/layout.py (``build``, which the runtime reads) all take them
from this module. Blades are named by ``codegen.algebra``'s identifier-safe names (i = ∞, o = 0).
Importing it does not import sympy.
"""
from __future__ import annotations

#: a similarity versor T R D (motor × dilator): the 12 blades the product closes in (design.md §2)
VERSOR = ("s", "e12", "e13", "e23", "e1i", "e2i", "e3i", "e123i", "eio", "e12io", "e13io", "e23io")
MOTOR = VERSOR[:8]                               # T R: the versor without its dilator blades
ROTOR = VERSOR[:4]
PLANE = ("e1", "e2", "e3", "ei")                 # dual plane n + d e∞ stored as (n1, n2, n3, d)
LOG = ("e12", "e13", "e23", "e1i", "e2i", "e3i", "eio")
AFFINE_LABELS = tuple(f"A[{r},{c}]" for r in range(3) for c in range(4))    # a 3×4 map, row-major
