"""Drill holes through a skinned mesh (the bit: a radius around a segment)."""
from .api import (MAX_NEW_VERTICES, NEW_VERTEX, RIM_STEP, SMALLEST_RADIUS_ROUNDINGS, DrillResult, drill, drill_details,
                  predicted_new_vertices, smallest_radius)
from .bit import Bit

__all__ = ["drill", "drill_details", "DrillResult", "Bit", "NEW_VERTEX", "RIM_STEP", "MAX_NEW_VERTICES",
           "SMALLEST_RADIUS_ROUNDINGS", "predicted_new_vertices", "smallest_radius"]
