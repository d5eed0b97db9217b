"""Cut a skinned mesh with a plane into two rigs."""
from .api import ON_PLANE_TOLERANCE, PLACEMENT_TOLERANCE, PlaneMissesMeshWarning, cut, cut_details
from .result import CAP_VERTEX, NEW_VERTEX, CutResult

__all__ = ["cut", "cut_details", "CutResult", "PlaneMissesMeshWarning", "NEW_VERTEX", "CAP_VERTEX",
           "ON_PLANE_TOLERANCE", "PLACEMENT_TOLERANCE"]
