"""Built-in kernels written in the kernel language (``codegen.language``): the ones it says as plainly
as the algebra does. The others stay with the builder (``ir.KernelBuilder``) because they need what the
language cannot say yet: named intermediates that stop the expansion (the idempotent split of the
sandwiches, coordinates relative to a vertex), named stages with a fixed layout (``versor_to_affine``),
or branches chosen by hand (exp, log, Shepperd).

Each ``@kernel`` here keeps the argument names, layouts and output order that generated/kernels.py's
callers rely on; the builder versions these replaced are gone (one definition per kernel).
"""
from __future__ import annotations

from .language import cga, kernel


@kernel
def versor_translator(t: cga.Vector) -> cga.Versor:
    """Translator T(t) = 1 − ½ t e∞ as a versor; t : (3,)."""
    return 1 - t * cga.einf / 2


@kernel
def gp_motor_motor(a: cga.Motor, b: cga.Motor) -> cga.Motor:
    """Geometric product a b of two motors (b applies first)."""
    return a * b


@kernel
def gp_versor_versor(a: cga.Versor, b: cga.Versor) -> cga.Versor:
    """Geometric product a b of two versors (b applies first)."""
    return a * b


@kernel
def reverse_versor(v: cga.Versor) -> cga.Versor:
    """Reverse Ṽ (grades 2 and 3 change sign)."""
    return ~v


@kernel
def inverse_versor(v: cga.Versor) -> cga.Versor:
    """Inverse Ṽ / ⟨V Ṽ⟩₀ (exact for versors, whose V Ṽ is a scalar)."""
    return ~v / (v * ~v).grade(0)


@kernel
def plane_from_normal_distance(n: cga.Vector, d: cga.Scalar) -> cga.Plane:
    """Dual plane n̂ + d e∞ (n normalised, d scaled to match) of {x : n·x = d}."""
    return (n + d * cga.einf) / cga.sqrt(n | n)


@kernel
def point_plane_distance(plane: cga.Plane, x: cga.Point) -> cga.Scalar:
    """Signed distance up(x)·π = n·x − d of a point from a unit dual plane π = n + d e∞."""
    return x | plane


def built(spec):
    """A catalogue entry (a function returning the Kernel IR) for a language kernel."""
    def make():
        from .trace import compile_kernel                    # sympy: only when the catalogue is built
        return compile_kernel(spec).kernel
    make.__name__ = spec.name
    return make
