"""The walls of a hole: the part of the bit's surface inside the model, joined to the rims.

A point of the bit's surface is (θ, σ), its angle around the axis and its height along the profile
(``bit_surface.Frame``). The rims (``rim.py``) are loops of the mesh's new boundary on that surface
(``bit_surface.Loop``), chained as ``loops.directed_loops`` chains edges, where the mesh is closed
around the bit:

* a loop that winds once around the axis is where a surface crosses it. The boundary of a surface
  around a hole runs clockwise seen from the side the surface faces, so the loop's winding about the
  travel (+1 or -1) is the step the model's winding number takes there along the axis (+1 entering an
  outward-wound shell, -1 leaving it; the other way round for an inward-wound one). From the winding
  number at the bit's back pole (0 where it lies outside the model's box: no global step; else the
  solid-angle sum over all the faces, ``inside.winding_number``), each loop either opens a level
  (the winding number moves away from 0: the bit enters a solid, of either winding) or closes the last
  one opened, and a tunnel joins the two (``_matched``): a shell of either winding, several disjoint
  ones, one inside another, are each closed; shells that intersect one another are joined across.
  Levels still open at the tip are joined to its pole (a blind hole's wall and round bottom) where the
  winding number at that pole, found directly, agrees; levels open below the lowest loop run down to
  the back's pole (a bit that starts inside the model). Where the direct count disagrees (a surface wound
  against its neighbours, an open mesh), the stretches between loops are inside and outside in turn
  (``_alternating``), and a last loop above which the model's winding number is 0 is left open (a
  hole through an open surface; counted as unclosed);
* a tunnel is made of rings at heights between the two loops' (``tunnel.py``): columns ``step`` apart
  around the axis (the rim's resolution), rings ``axial`` apart along it (the mesh's), zipped together
  by angle; its vertices lie on the bit's surface;
* a loop that does not wind around the axis (a bit grazing the model's side) is filled with the part of
  the surface it encloses: its two chains zipped by angle (or ear-clipped in the unrolled (r θ, σ)
  plane and refined, ``_refine_fills``);
* a rim that runs into an open boundary of the mesh is a chain, not a loop: it gets no wall, and no
  tunnel passes its heights (``build_walls``).

Wall faces are wound as the faces around their rims (each rim edge once each way): facing the axis
(their outside is the hole) in an outward-wound solid. Wall vertices are rows of their own (the rims'
positions, other normals): described, for weights and attributes, by the rim rows nearest in angle on
the loops they lie between; their normal points to the axis. What the walls leave unclosed, the edges
of the loops and walls without exactly two faces (a loop no wall joins, an edge two walls share), is
counted (``DrillResult.unclosed_edges``, ``OpenRimWarning``).
"""
from __future__ import annotations

import math

import numpy as np

from ..._shared.jit import I2, inlined, kernel
from ...errors import InternalError
from ...tolerances import tol
from ..cut.cap import _ear_clip
from ..loops import directed_loop_edges
from .bisection import code_table, pair, slot
from .bit_surface import Frame, Loop, loops
from .patch import LOW_BITS, Patch, edge_codes
from .refine import MAX_ROUNDS, bisect_marked
from .rim import rim_loop_edges
from .strips import zip_chains
from .tunnel import tunnel

#: a wall face's input face (``Patch.face_source``): a tunnel's, or a fill's (the inside of a loop that
#: does not wind around the axis)
WALL, WALL_FILL = -1, -2


def build_walls(patch: Patch, rim, bit, step: float, axial: float, winding) -> tuple:
    """Add the holes' walls to the patch (module docstring): rings ``axial`` apart along the axis, columns
    ``step`` around it; ``winding(point (3,)) -> float`` is the input model's winding number at a point.
    A rim that runs into an open boundary of the mesh is a chain, not a loop: it gets no wall, and no
    loop is joined to another, or to a pole, across its heights (the wall there would have no rim to end
    on). Returns (the number of wall faces, of such chains, of the loops' and walls' edges left without
    exactly two faces: ``_unclosed``)."""
    frame = Frame(bit)
    loops, chains, rim_pairs = _rim_loops(patch, rim, frame)
    before = len(patch.faces)
    around = sorted((loop for loop in loops if loop.winding != 0), key=lambda loop: float(loop.sigma.mean()))
    for a, b, facing in _tunnels(frame, around, winding):
        low = frame.bottom if a is None else float(a.sigma.max())
        beyond = frame.top if b is None else float(b.sigma.min())
        if not any(chain.max() > low and chain.min() < beyond for chain in chains):
            tunnel(patch, frame, a, b, step, axial, facing, WALL)
    fills = [loop for loop in loops if loop.winding == 0]
    for loop in fills:
        _fill(patch, frame, loop, step)
    if fills:
        _refine_fills(patch, frame, step)
    walls = patch.row_point[patch.faces[before:]]
    return len(walls), len(chains), _unclosed(walls, rim_pairs)


def _tunnels(frame: Frame, around: list, winding) -> list:
    """The tunnels (a, b, facing) that wall the loops ``around`` (winding loops, by height): a None for
    the back's pole, b None for the tip's, ``facing`` whether its faces face the axis (module
    docstring)."""
    if not around:
        return []
    below = _winding_at(frame, winding, frame.bottom)
    tunnels, still_open, at_tip = _matched(around, below)
    if not still_open:
        return tunnels
    tip = _winding_at(frame, winding, frame.top)
    if tip == at_tip:
        return tunnels + [(a, None, facing) for a, facing in still_open if a is not None]
    return _alternating(around, below, tip)


def _matched(around: list, below: int) -> tuple:
    """Each winding loop of ``around`` (by height) opens a level or closes the last one opened, from
    ``below`` (the winding number at the back pole; levels it opens have no loop: None). Returns (the
    tunnels (opening loop, closing loop, facing) of the closed levels, the levels (opening loop, facing)
    still open at the top, the winding number there). A loop that winds more than once is left."""
    levels = [(None, below > 0)] * abs(below)
    tunnels, count = [], below
    for loop in around:
        if abs(loop.winding) != 1:
            continue
        after = count + loop.winding
        if abs(after) > abs(count):
            levels.append((loop, after > 0))
        else:
            opening, facing = levels.pop()
            tunnels.append((opening, loop, facing))
        count = after
    return tunnels, levels, count


def _alternating(around: list, below: int, tip: int) -> list:
    """Where the winding numbers do not add up (a surface wound against its neighbours, an open mesh):
    the stretches of the bit between loops of ``around``, inside and outside in turn from the one under
    the lowest (inside where ``below``, at the back pole, is odd), each inside one a tunnel (facing the
    axis as its lower loop's winding, or its upper's, says); the last to the tip's pole only where the
    winding number there, ``tip``, is not 0, else that loop is left open (a hole in an open surface)."""
    bounds = [None] + around + [None]
    return [(a, b, a.winding > 0 if a is not None else b.winding < 0)
            for i, (a, b) in enumerate(zip(bounds, bounds[1:]))
            if (abs(below) + i) % 2 == 1 and not (a is None and b is None) and not (b is None and tip == 0)]


def _winding_at(frame: Frame, winding, sigma: float) -> int:
    """The input model's winding number (rounded) at a pole of the bit (σ its back's or its tip's): where
    a wall would end (the axis between the loops may pass through surfaces whose rims do not wind
    around it, a part of the mesh wholly inside the bit through others)."""
    return int(round(winding(frame.axis_point(sigma))))


def _rim_loops(patch: Patch, rim, frame: Frame) -> tuple:
    """The loops of boundary edges between rim points (rows ``rim``), chained over their points (welded:
    seams are one) as ``loops.directed_loops`` chains edges (``rim.rim_loop_edges``), as ``Loop``s;
    the heights σ (k,) of each chain that does not close; the loops' edges as pairs of points (e, 2). A
    chain is found as a loop too: its edges there and back (the chains' first edges first, so that each
    comes round whole)."""
    tails, heads, a, b, edges, offsets = rim_loop_edges(patch.faces, patch.row_point, rim, patch.n_points)
    chains = []
    if len(edges) < len(a):
        left = np.ones(len(a), bool)
        left[edges] = False
        left = np.flatnonzero(left)
        first = np.isin(a[left], b[left], invert=True)
        left = np.concatenate([left[first], left[~first]])
        there_and_back = np.concatenate([a[left], b[left]])
        walked, ends = directed_loop_edges(there_and_back, np.concatenate([b[left], a[left]]))
        chains = [frame.coordinates(patch.point_array()[there_and_back[walked[i:j]]])[1]
                  for i, j in zip(ends[:-1], ends[1:])]
    corners = a[edges]
    return (loops(frame, tails[edges], corners, patch.point_array()[corners], offsets), chains,
            np.column_stack([corners, b[edges]]))


@kernel((I2, I2), cost=0.2)
def _unclosed(walls, rim_pairs):
    """The edges that do not have exactly two faces among the wall faces ``walls`` (W, 3) (points) and
    the faces on the far side of the loops' rim edges ``rim_pairs`` (e, 2) (points; one each: a rim
    edge is a boundary edge of the mesh): a loop without a wall, an edge two walls share."""
    table = code_table(3 * walls.shape[0] + rim_pairs.shape[0])
    counts = np.zeros(table.shape[0], np.int64)
    for i in range(rim_pairs.shape[0]):
        _count(table, counts, rim_pairs[i, 0], rim_pairs[i, 1])
    for f in range(walls.shape[0]):
        for k in range(3):
            _count(table, counts, walls[f, k], walls[f, (k + 1) % 3])
    out = 0
    for at in range(table.shape[0]):
        out += table[at] >= 0 and counts[at] != 2
    return out


@inlined
def _count(table, counts, p, q):
    """Count the edge between points p and q in ``table`` (a ``code_table``) and ``counts``. Its key is
    its ``pair`` code with the lower id's multiplicative hash folded into the low half (a bijection:
    the high half stays), so that the table's slots spread over the walls' consecutive point ids."""
    code = pair(p, q)
    code ^= (((code >> 32) * 0x9E3779B1) & LOW_BITS)
    at = slot(table, code)
    table[at] = code
    counts[at] += 1


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
    # counter-clockwise in (r θ, σ) faces away from the axis (∂θ × ∂σ is the outward radial); the fill
    # runs along its rim against the mesh's faces, so it winds against the loop: clockwise where the
    # loop (in the faces' direction) is counter-clockwise, facing the axis (an outward-wound surface)
    clockwise = _area(np.column_stack([frame.r * loop.unwrapped, loop.sigma])) >= 0.0
    flip = turn > 0.0 if clockwise else turn < 0.0
    triangles[flip] = triangles[flip][:, [0, 2, 1]]
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
