"""Cut a skinned mesh with a plane into two rigs."""
from .api import (CutResult, PlaneMissesMeshWarning, cut, cut_details, ON_PLANE_TOLERANCE,
                  PLACEMENT_TOLERANCE)

__all__ = ["cut", "cut_details", "CutResult", "PlaneMissesMeshWarning", "ON_PLANE_TOLERANCE",
           "PLACEMENT_TOLERANCE"]
