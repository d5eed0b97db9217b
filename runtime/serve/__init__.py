"""``cgaskin serve``: a local page where the user cuts, tears and drills a playing model; Python does
the surgery (one ``Surgery`` per tab) and sends back only the rows and faces that changed.

Imported on first use only (the CLI imports it when ``serve`` runs): ``import cgaskin`` loads neither
it nor ``websockets``.
"""
from ..errors import LimitError
from .limits import Limits
from .server import Server, serve_page
from .tab import Tab

__all__ = ["LimitError", "Limits", "Server", "Tab", "serve_page"]
