"""One way to warn: attributed to the user's line, however deep inside cgaskin the cause was found.

A fixed ``stacklevel`` is right for one call path only (``tear`` -> ``tear_stroke`` blamed tear.py;
``cut_details`` called directly was off by one). ``warn`` walks up the stack past every frame of a
``cgaskin`` module instead (as scikit-image's ``warn_external`` does).
"""
from __future__ import annotations

import sys
import warnings

__all__ = ["warn"]


def _is_ours(frame) -> bool:
    name = frame.f_globals.get("__name__", "")
    return name == "cgaskin" or name.startswith("cgaskin.")


def warn(message: str, category: type = UserWarning) -> None:
    """``warnings.warn(message, category)`` attributed to the first caller outside cgaskin."""
    level, frame = 2, sys._getframe(1)        # stacklevel 2 is the frame that called warn()
    while frame is not None and _is_ours(frame):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
