"""The build step: symbolic algebra -> generated numba kernels (needs the ``build`` extra: sympy).

Importing this package is cheap (no sympy): it re-exports the algebras, whose product tables are
computed on first use, and the kernel language. ``cga`` is the conformal algebra G(4,1) in the null
basis carrying the language's types (Point, Plane, Versor, ...) and constants; it equals
``algebras.cga`` and shares its tables; ``pga`` is G(3,0,1) with its types (``codegen.language_pga``). ``build_catalogue`` needs sympy and is imported on first use;
``verify_catalogue`` (``codegen.verify``) needs sympy and clifford.
"""
from .algebras import Algebra, InvalidAlgebraError
from .errors import CodegenError
from .language import ConformalAlgebra, KernelSpec, cga, kernel
from .language_pga import ProjectiveAlgebra, pga

__all__ = ["Algebra", "InvalidAlgebraError", "cga", "pga", "ConformalAlgebra", "ProjectiveAlgebra", "KernelSpec", "kernel",
           "build_catalogue", "verify_catalogue", "CodegenError"]


def __getattr__(name):
    if name == "build_catalogue":
        from .catalogue_build import build_catalogue
        return build_catalogue
    if name == "verify_catalogue":                    # needs sympy and clifford (the test extra)
        from .verify import verify_catalogue
        return verify_catalogue
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
