"""Kernel catalogues the codegen tests build: the README's example, as a user copies it."""

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
