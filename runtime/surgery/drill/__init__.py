"""Drill holes through a skinned mesh (the bit: a radius around a segment)."""
from .api import NEW_VERTEX, RIM_STEP, DrillResult, drill, drill_details
from .bit import Bit

__all__ = ["drill", "drill_details", "DrillResult", "Bit", "NEW_VERTEX", "RIM_STEP"]
