"""Chaining directed edges into closed loops: a mesh's boundary (``Topology.boundary_loops``), a cut's
cap outline, a drill's rims.

``directed_loops`` gives the loops as vertex lists, ``directed_loop_edges`` as edge indices in arrays;
both walk in compiled code (``_walk``), which stops and asks the caller's ``choose`` where several
unused edges leave the vertex reached (loops touching at a vertex). ``chained_edges`` is the walk with
the default choice in one compiled call, for compiled callers (the drill's rims).
"""
from __future__ import annotations

import numpy as np

from .._shared.jit import B1, I1, b1, helper, kernel

__all__ = ["directed_loops", "directed_loop_edges", "chained_edges"]


def directed_loops(start, end, choose=None) -> list:
    """Chain directed edges start[i] -> end[i] into closed loops (lists of vertex ids).

    Where a vertex starts several unused edges (loops touching at a vertex), ``choose(previous, vertex,
    candidates)`` picks the next one (an index into ``candidates``, which are edge indices); by default
    the first. Geometry-aware callers pass the sharpest turn (see ``cut``), so that touching loops come
    out as separate simple loops. Edges left in chains that do not close are dropped.
    (``directed_loop_edges`` gives the loops as edge indices, in arrays.)
    """
    edges, offsets = directed_loop_edges(start, end, choose)
    vertices = np.asarray(start)[edges].tolist()
    return [vertices[a:b] for a, b in zip(offsets[:-1].tolist(), offsets[1:].tolist())]


#: how ``_walk`` stopped: every edge walked; at a vertex where ``choose`` picks among several edges
WALKED, TO_CHOOSE = 0, 1
#: the entries of ``_walk``'s state: the loop's first edge, the edge walked (-1: between loops), the
#: edges kept, the loops kept, the edge picked for a pending choice (-1: none), the candidates waiting
FIRST, AT, KEPT, LOOPS, PICK, WAITING = range(6)


def directed_loop_edges(start, end, choose=None) -> tuple:
    """``directed_loops`` as edge indices: (the edges (k,) int64 of the loops, each loop in order from its
    first edge (the lowest not taken by an earlier loop or chain), offsets (l + 1,) int64: loop i is
    edges[offsets[i]:offsets[i + 1]]). One walk (``_walk``, compiled), which stops where ``choose`` is
    given and must pick (without it: ``chained_edges``, which compiled code calls too)."""
    start = np.ascontiguousarray(start, dtype=np.int64).reshape(-1)
    end = np.ascontiguousarray(end, dtype=np.int64).reshape(-1)
    if choose is None:
        return chained_edges(start, end)
    by_start, sorted_start, used, edges, offsets, state, candidates = _walk_arrays(start, end)
    while _walk(start, end, by_start, sorted_start, used, edges, offsets, state, candidates, True) == TO_CHOOSE:
        at, waiting = int(state[AT]), candidates[:state[WAITING]].tolist()
        state[PICK] = waiting[choose(int(start[at]), int(end[at]), waiting)]
    return edges[:offsets[state[LOOPS]]].copy(), offsets[:state[LOOPS] + 1].copy()


@kernel((I1, I1), cost=0.3)
def chained_edges(start, end):
    """``directed_loop_edges(start, end)`` (the default choice) in one compiled call."""
    by_start, sorted_start, used, edges, offsets, state, candidates = _walk_arrays(start, end)
    _walk(start, end, by_start, sorted_start, used, edges, offsets, state, candidates, False)
    return edges[:offsets[state[LOOPS]]].copy(), offsets[:state[LOOPS] + 1].copy()


@kernel((I1, I1), cost=0.1)
def _walk_arrays(start, end):
    """``_walk``'s arrays for the edges start -> end (n,): the edges by start vertex (stable) and their
    starts, used (n,), edges (n,), offsets (n + 1,), the state, the candidates (n,)."""
    n = start.shape[0]
    by_start = np.argsort(start, kind="mergesort")      # (the edges leaving a vertex, in their order)
    state = np.zeros(6, np.int64)
    state[AT], state[PICK] = -1, -1
    return (by_start, start[by_start], np.zeros(n, np.bool_), np.empty(n, np.int64), np.zeros(n + 1, np.int64), state,
            np.empty(n, np.int64))


@kernel((I1, I1, I1, I1, B1, I1, I1, I1, I1, b1), cost=0.2)
def _walk(start, end, by_start, sorted_start, used, edges, offsets, state, candidates, choosing):
    """Chain the edges start -> end (n,) into loops (``directed_loop_edges``) from ``state`` (``FIRST`` ...
    ``WAITING``; updated, as ``used`` (n,), ``edges`` (n,) and ``offsets`` (n + 1,) are): each loop starts
    at the lowest unused edge and goes on by an unused edge leaving the vertex reached (``by_start`` (n,)
    the edges by start vertex, ``sorted_start`` (n,) their starts) or closes at its first; where several
    leave it, the first if it is one of them, else the first unused, or, ``choosing``, the caller picks
    (returns ``TO_CHOOSE`` with the candidates in ``candidates`` and their number in ``WAITING``; it
    writes its pick to ``PICK`` and calls again). A chain that does not close is dropped (its edges
    stay used). Returns ``WALKED`` when every edge is walked."""
    n = start.shape[0]
    first, at, kept, loops = state[FIRST], state[AT], state[KEPT], state[LOOPS]
    while True:
        if state[PICK] >= 0:                    # (resumed: the caller picked)
            pick = state[PICK]
            state[PICK] = -1
        else:
            if at < 0:
                while first < n and used[first]:
                    first += 1
                if first >= n:
                    state[FIRST], state[AT], state[KEPT], state[LOOPS] = first, at, kept, loops
                    return WALKED
                at, kept = first, offsets[loops]
            used[at] = True
            edges[kept] = at
            kept += 1
            vertex = end[at]
            count = 0
            for q in range(_lower_bound(sorted_start, vertex), n):
                if sorted_start[q] != vertex:
                    break
                j = by_start[q]
                if not used[j] or j == first:
                    candidates[count] = j
                    count += 1
            if count == 0:                      # an open chain: dropped
                at = -1
                first += 1
                continue
            pick = candidates[0]
            if count > 1:
                if choosing:
                    state[FIRST], state[AT], state[KEPT], state[LOOPS], state[WAITING] = first, at, kept, loops, count
                    return TO_CHOOSE
                for c in range(count):
                    if candidates[c] == first:
                        pick = first
        if pick == first:
            loops += 1
            offsets[loops] = kept
            at = -1
            first += 1
        else:
            at = pick


@helper
def _lower_bound(values, x):
    """The first index of ascending ``values`` (n,) at which ``x`` could be inserted (np.searchsorted)."""
    lo, hi = 0, values.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo
