"""Kernel catalogues the codegen tests build: the kernel compiler guide's example (docs/guide/kernel_compiler.rst), as a
user copies it."""

README_CATALOGUE = '''
from cgaskin.codegen import cga, kernel

@kernel
def reflect(plane: cga.Plane, x: cga.Point) -> cga.Point:
    """Reflect a point in a plane."""
    return -plane * x * plane

@kernel(uniform=("V",))
def move(V: cga.Versor, x: cga.Point) -> cga.Point:
    """Move points by one versor."""
    return V * x * ~V
'''

PGA_CATALOGUE = '''
from cgaskin.codegen import kernel, pga

@kernel(uniform=("M",))
def move(M: pga.Motor, x: pga.Point) -> pga.Point:
    """Move a point by a motor."""
    return M * x * ~M

@kernel
def reflect(p: pga.Plane, x: pga.Point) -> pga.Point:
    """Reflect a point in a plane."""
    return -p * x * p

@kernel
def meet(a: pga.Plane, b: pga.Plane) -> pga.Line:
    """The line where two planes meet."""
    return a ^ b

@kernel
def compose(a: pga.Motor, b: pga.Motor) -> pga.Motor:
    """b, then a."""
    return a * b
'''
