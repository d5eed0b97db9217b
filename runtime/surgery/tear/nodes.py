"""Codes of the tear's path nodes, shared by its steps.

The compiled helpers take these codes (and every other small integer) as np.int64, never as Python
int literals: numba compiles a separate copy of a helper for each literal value it is called with
(also for a loop counter that starts at a literal: ``n = 0`` gives one copy for Literal[int](0) and
one for int64, so such counters start at ``np.int64(0)``).
Helpers that only other kernels call are compiled with no_cpython_wrapper=True: numba then builds
no Python entry point for them, which shortens a cold start by about a tenth (cgaskin.precompile).
"""
import numpy as np

# path node kinds
VERTEX, EDGE, FACE = np.int64(0), np.int64(1), np.int64(2)
# how a path segment runs from the previous node: across a face, or along an edge in the plane
NO_CARRIER, FACE_CARRIER, EDGE_CARRIER = np.int64(-1), np.int64(0), np.int64(1)
