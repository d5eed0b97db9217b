"""A newcomer's catalogue, written only from the README's "Write your own kernels" section.

Graphics / surgical-simulation kernels: project onto a plane, invert in a sphere, meet two planes,
move points by one rigid motor, distance of a point to a plane (CGA); reflect in a plane, compose two
motors and move points by one motor (PGA).
"""
from cgaskin.codegen import cga, kernel, pga


@kernel
def project_onto_plane(plane: cga.Plane, x: cga.Point) -> cga.Point:
    """Orthogonal projection of a point onto a plane (any normal length)."""
    return x - (x | plane) * plane / (plane * plane)


@kernel
def invert_in_sphere(sphere: cga.Sphere, x: cga.Point) -> cga.Point:
    """Inversion of a point in a sphere: c + r^2 (x - c) / |x - c|^2."""
    return sphere * x * sphere


@kernel
def meet_planes(p: cga.Plane, q: cga.Plane) -> cga.Line:
    """The line where two planes meet."""
    return p ^ q


@kernel(uniform=("M",))
def rigid_move(M: cga.Motor, x: cga.Point) -> cga.Point:
    """Rotate then translate points by one motor."""
    return M * x * ~M


@kernel
def plane_distance(plane: cga.Plane, x: cga.Point) -> cga.Scalar:
    """Unsigned distance of a point to a plane whose normal need not be unit."""
    return cga.abs(x | plane) / cga.sqrt(plane * plane)


@kernel
def pga_reflect(p: pga.Plane, x: pga.Point) -> pga.Point:
    """Reflect a point in a plane (PGA)."""
    return p * x * p


@kernel
def pga_compose(A: pga.Motor, B: pga.Motor) -> pga.Motor:
    """The motor that moves by B, then by A (PGA)."""
    return A * B


@kernel(uniform=("M",))
def pga_move(M: pga.Motor, x: pga.Point) -> pga.Point:
    """Move points by one motor (PGA)."""
    return M * x * ~M
