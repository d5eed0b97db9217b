"""The walls of a hole: the part of the bit's surface inside the model, joined to the rims.

A point of the bit's surface is (θ, σ), its angle around the axis and its height along the profile
(``bit_surface.Frame``). The rims (``rim.py``) are loops of the mesh's new boundary on that surface
(``bit_surface.Loop``), where the mesh is closed around the bit:

* a loop that winds once around the axis is an entry or an exit: the boundary of a surface around a
  hole runs clockwise seen from the side the surface faces, so on an outward-facing surface an entry
  (facing the bit as it comes) winds positively about the travel, an exit negatively. The loops are
  ordered by height; an entry followed by an exit is joined to it by a tunnel; an entry followed by
  nothing (or by another entry: a surface facing the wrong way) is joined to the tip (a blind hole's
  wall and round bottom) or to that loop only where the axis beyond it is inside the input model (its
  winding number, a solid-angle sum over all its faces: the one global step, taken only then);
* a tunnel is made of rings at heights between the two loops' (columns and rings about ``step``
  apart), zipped together by angle (``tunnel.py``); its vertices lie on the bit's surface;
* a loop that does not wind around the axis (a bit grazing the model's side) is filled with the part of
  the surface it encloses: its two chains zipped by angle (or ear-clipped in the unrolled (r θ, σ)
  plane and refined, ``_refine_fills``);
* a rim that runs into an open boundary of the mesh is a chain, not a loop: it gets no wall, and no
  tunnel passes its heights (``build_walls``).

Wall faces face the axis (their outside is the hole). Wall vertices are rows of their own (the rims'
positions, other normals): described, for weights and attributes, by the rim rows nearest in angle on
the loops they lie between; their normal points to the axis.
"""
from __future__ import annotations

import math

import numpy as np

from ...errors import InternalError
from ...tolerances import tol
from ..cut.cap import _ear_clip
from .bit_surface import Frame, Loop, loops
from .patch import LOW_BITS, Patch, edge_codes
from .refine import MAX_ROUNDS, bisect_marked
from .rim import rim_loops
from .strips import zip_chains
from .tunnel import tunnel

#: the winding about the bit's travel of a rim where it enters an outward-facing surface
ENTRY = 1
#: a wall face's input face (``Patch.face_source``): a tunnel's, or a fill's (the inside of a loop that
#: does not wind around the axis)
WALL, WALL_FILL = -1, -2


def build_walls(patch: Patch, rim, bit, step: float, inside) -> tuple:
    """Add the holes' walls to the patch (module docstring); ``inside(point (3,)) -> bool`` says whether a
    point is inside the input model. A rim that runs into an open boundary of the mesh is a chain, not
    a loop: it gets no wall, and no loop is joined to another, or to the tip, across its heights (the
    wall there would have no rim to end on). Returns (the number of wall faces, of such chains)."""
    frame = Frame(bit)
    loops, chains = _rim_loops(patch, rim, frame)
    before = len(patch.faces)
    around = sorted((loop for loop in loops if loop.winding != 0), key=lambda loop: float(loop.sigma.mean()))
    for a, b in zip(around, around[1:] + [None]):      # None: the tip's pole
        if a.winding != ENTRY:
            continue
        low, beyond = float(a.sigma.max()), frame.top if b is None else float(b.sigma.min())
        if any(chain.max() > low and chain.min() < beyond for chain in chains):
            continue                                    # a chain between: the wall would leave through it
        if b is not None and b.winding != ENTRY:
            tunnel(patch, frame, a, b, step, WALL)      # an entry, then an exit
        elif inside(frame.axis_point(0.5 * (low + beyond))):
            tunnel(patch, frame, a, b, step, WALL)      # a blind hole (or a surface facing the wrong way)
    fills = [loop for loop in loops if loop.winding == 0]
    for loop in fills:
        _fill(patch, frame, loop, step)
    if fills:
        _refine_fills(patch, frame, step)
    return len(patch.faces) - before, len(chains)


def _rim_loops(patch: Patch, rim, frame: Frame) -> tuple:
    """The loops of boundary edges between rim points (rows ``rim``), as ``Loop``s (point ids welded:
    seams are one; ``rim.rim_loops``), and the heights σ (k,) of each chain that does not close."""
    on_rim = np.zeros(patch.n_points, bool)
    on_rim[patch.row_point[rim]] = True
    rows, points, offsets, n_loops = rim_loops(patch.faces, patch.row_point, on_rim)
    positions = patch.point_array()[points]
    chains = [frame.coordinates(positions[i:j])[1] for i, j in zip(offsets[n_loops:-1], offsets[n_loops + 1:])]
    return loops(frame, rows, points, positions, offsets[:n_loops + 1]), chains


def _loop_rows(patch: Patch, loop: Loop) -> np.ndarray:
    """Wall rows (k,) at the loop's own corners (the rim's points, rows of their own)."""
    first = patch.new_rows(loop.points, loop.rows, loop.rows, 0.0)
    return np.arange(first, first + len(loop.rows))


def _fill(patch: Patch, frame: Frame, loop: Loop, step: float) -> None:
    """The surface a loop that does not wind around the axis encloses. Split at its least and greatest
    angle, a loop is usually two chains along which the angle only grows: they are zipped by angle,
    faces narrow across the curvature and long along the straight axis. A loop longer along the axis
    than across it (a bit grazing lengthwise), or one whose angle chains do not only grow, is split at
    its least and greatest height instead, with chains between them about a ``step`` apart across the
    curvature (``_chains_between``), each zipped to the next by height. Otherwise the loop is
    ear-clipped in (r θ, σ). Edges that then span the curvature are bisected (``_refine_fills``)."""
    for point, theta, sigma in zip(loop.points, loop.unwrapped, loop.sigma):
        patch.fill_params[int(point)] = np.array([theta, sigma])     # (the fill's refinement halves them)
    rows = _loop_rows(patch, loop).tolist()
    n, triangles = len(rows), None
    theta, sigma = loop.unwrapped, loop.sigma
    keys = (loop.unwrapped, loop.sigma)          # across the axis, else along it (a bit grazing lengthwise)
    if np.ptp(loop.sigma) > frame.r * np.ptp(loop.unwrapped):
        keys = keys[::-1]                        # (a loop longer along the axis than across: along it first)
    for key in keys:
        first, last = int(np.argmin(key)), int(np.argmax(key))
        chains = [[(first + i) % n for i in range((last - first) % n + 1)],
                  [(first - i) % n for i in range((first - last) % n + 1)]]
        steps = [np.diff(key[chain]) for chain in chains]
        # (along the axis a chain may step across at one height: the rim crossing a ring of edges)
        if all(np.all(d >= 0.0) if key is loop.sigma else np.all(d > 0.0) for d in steps):
            if key is loop.unwrapped:
                triangles = zip_chains(key, *chains)
            else:
                chains, theta, sigma = _chains_between(patch, frame, loop, rows, chains, step)
                triangles = [tri for lower, upper in zip(chains, chains[1:])
                             for tri in zip_chains(sigma, lower, upper)]
            break
    if triangles is None:
        xy = np.column_stack([frame.r * loop.unwrapped, loop.sigma])
        order = np.arange(n) if _area(xy) > 0.0 else np.arange(n)[::-1]
        triangles = order[_ear_clip(np.ascontiguousarray(xy[order]), order.astype(np.int64), tol.min_sine)]
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    x, y = frame.r * theta[triangles], sigma[triangles]
    turn = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (y[:, 1] - y[:, 0]) * (x[:, 2] - x[:, 0])
    # counter-clockwise in (r θ, σ) faces away from the axis (∂θ × ∂σ is the outward radial): reversed
    triangles[turn > 0.0] = triangles[turn > 0.0][:, [0, 2, 1]]
    patch.add_faces(np.asarray(rows, np.int64)[triangles], WALL_FILL)


def _chains_between(patch: Patch, frame: Frame, loop: Loop, rows: list, chains: list, step: float) -> tuple:
    """Chains between a lengthwise fill's two chains (corner indices from its least to its greatest
    height), at the first chain's heights and angles evenly between the two chains' there, so that no
    edge across spans more than ``step`` of the curvature; their rows blend the first chain's row and
    the other chain's row nearest in height. Appends the new rows to ``rows``; returns (the chains from
    the first to the other, θ and σ of every index)."""
    lower, upper = chains
    theta, sigma = loop.unwrapped, loop.sigma
    across = np.interp(sigma[lower], sigma[upper], theta[upper]) - theta[lower]
    count = max(1, int(math.ceil(frame.r * float(np.abs(across).max()) / step)))
    inner = lower[1:-1]                                   # (the two chains share their first and last corner)
    nearest = np.asarray(upper)[np.abs(sigma[upper][None, :] - sigma[inner][:, None]).argmin(axis=1)]
    out, thetas, sigmas = [lower], [theta], [sigma]
    for j in range(1, count):
        t = j / count
        ring_theta, ring_sigma = theta[inner] + t * across[1:-1], sigma[inner]
        first = patch.add_points(frame.points(ring_theta, ring_sigma))
        start, row_ids = len(rows), np.asarray(rows, np.int64)
        first_row = patch.new_rows(first + np.arange(len(inner)), row_ids[inner], row_ids[nearest], t)
        rows.extend(range(first_row, first_row + len(inner)))
        for i in range(len(inner)):
            patch.fill_params[first + i] = np.array([ring_theta[i], ring_sigma[i]])
        out.append([lower[0]] + list(range(start, len(rows))) + [lower[-1]])
        thetas.append(ring_theta)
        sigmas.append(ring_sigma)
    out.append(upper)
    return out, np.concatenate(thetas), np.concatenate(sigmas)


def _area(xy) -> float:
    """The signed area of polygon xy (k, 2) (> 0: counter-clockwise)."""
    return 0.5 * float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))


def _curved_extent(frame: Frame, a, b) -> float:
    """How far an edge between surface points (θ, σ) a and b runs across the surface's curvature: its
    angle times the radius on the cylinder (which is straight along the axis: an edge along it lies on
    it), its chord where it reaches onto a round end (a sphere: near its pole an angle spans little, and
    a measure in (θ, σ) would never shrink under the bisection of the longest edges in space)."""
    if min(a[1], b[1]) < 0.0 or max(a[1], b[1]) > frame.length:
        return float(np.linalg.norm(frame.point(*a) - frame.point(*b)))
    return frame.r * abs(float(a[0] - b[0]))


def _refine_fills(patch: Patch, frame: Frame, step: float) -> None:
    """Bisect the fills' inner edges that span more than ``step`` across the surface's curvature
    (``_curved_extent``; both faces of such an edge are fill faces), each midpoint the surface point
    halfway in (θ, σ) (a chord across a wide fill passes near the axis, where the direction to the
    surface is lost), until the fills follow the surface as closely as the rims do."""
    params = patch.fill_params

    def place(a, b) -> np.ndarray:
        halfway = 0.5 * (np.array([params[p] for p in a.tolist()]) + np.array([params[p] for p in b.tolist()]))
        params.update(zip(range(patch.n_points, patch.n_points + len(a)), halfway))
        return frame.points(halfway[:, 0], halfway[:, 1])

    for _ in range(MAX_ROUNDS):
        codes, fill = edge_codes(patch.face_points()), patch.face_source == WALL_FILL
        inner = np.setdiff1d(codes[fill], codes[~fill])         # a fill's inner edges (its loop's are the rim's)
        marked = [code for code in inner.tolist()
                  if _curved_extent(frame, params[code >> 32], params[code & LOW_BITS]) > step]
        if not marked:
            return
        bisect_marked(patch, np.array(marked, np.int64), place)
    raise InternalError(f"a hole's wall did not become finer than {step:g} in {MAX_ROUNDS} rounds")
