"""The build step: symbolic algebra -> generated numba kernels (needs the ``build`` extra: sympy).

Importing this package is cheap (no sympy): it re-exports the algebras, whose product tables are
computed on first use.
"""
from .algebras import Algebra, InvalidAlgebraError, cga, pga

__all__ = ["Algebra", "InvalidAlgebraError", "cga", "pga"]

# the kernel language (codegen/language.py): ``cga`` from here on is the same algebra (equal to
# algebras.cga, sharing its tables) carrying the types Point, Plane, Versor, ... and the constants
from .language import ConformalAlgebra, KernelSpec, cga, kernel  # noqa: E402

__all__ += ["ConformalAlgebra", "KernelSpec", "build_catalogue", "kernel"]


def __getattr__(name):
    """``build_catalogue`` (codegen/catalogue_build.py) needs sympy: imported on first use."""
    if name == "build_catalogue":
        from .catalogue_build import build_catalogue
        return build_catalogue
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
