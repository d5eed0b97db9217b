"""The viewer: one self-contained HTML page (three.js and the model inside) that plays a rig's clips,
shows its skeleton, weights, a live dilation and its open edges (``cgaskin view``, ``cgaskin.show``).

Imported on first use only (``cgaskin.show`` loads it lazily): ``import cgaskin`` reads no asset.
"""
from .model import rim_edges, view_html
from .page import SKINNING_MODES, page_html
from .show import View, show

__all__ = ["show", "View", "view_html", "page_html", "rim_edges", "SKINNING_MODES"]
