"""Tear a skinned mesh with a scalpel."""
from .stroke import (TEAR_LABEL, SNAP_TOLERANCE, PLACEMENT_TOLERANCE, TearPathError, TearPlacementWarning,
                     StrokeResult, TearResult, tear, tear_stroke, tear_topology)

__all__ = ["tear", "tear_stroke", "TearResult", "StrokeResult", "TearPathError", "TearPlacementWarning",
           "tear_topology", "TEAR_LABEL", "SNAP_TOLERANCE", "PLACEMENT_TOLERANCE"]
