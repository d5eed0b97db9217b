"""The build step: symbolic algebra -> generated numba kernels (needs the ``build`` extra: sympy).

Importing this package is cheap (no sympy): it re-exports the algebras, whose product tables are
computed on first use.
"""
from .algebras import Algebra, InvalidAlgebraError, cga, pga

__all__ = ["Algebra", "InvalidAlgebraError", "cga", "pga"]
