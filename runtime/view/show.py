"""``cgaskin.show``: the viewer page for notebooks (``_repr_html_``) and files (``save``)."""
from __future__ import annotations

import html
from pathlib import Path

from ..errors import InvalidInputError
from .model import view_html


class View:
    """A rig's viewer page. In a notebook it shows itself inline (an ``<iframe srcdoc>`` holding the
    whole page: three.js and the model inside, no request, no server); ``save(path)`` writes it as
    an .html file that opens offline in a browser.

    Parameters
    ----------
    page : str
        The page (what ``cgaskin view`` writes); kept as ``html``.
    height : int, optional
        The iframe's height in CSS pixels.

    Examples
    --------
    >>> view = cgaskin.show(cgaskin.capsule_arm(), height=360)
    >>> view.height, view.html.startswith("<!doctype html>")
    (360, True)
    """

    def __init__(self, page: str, height: int = 480):
        self.html = page
        self.height = int(height)

    def _repr_html_(self) -> str:
        # srcdoc: the page runs in its own document (its import map and blob: modules do not meet the
        # notebook's), without a server; html.escape(quote=True) makes it one attribute value
        return (f'<iframe srcdoc="{html.escape(self.html, quote=True)}" style="width: 100%; '
                f'height: {self.height}px; border: 0;" title="cgaskin view"></iframe>')

    def save(self, path) -> Path:
        """Write the page as an .html file.

        Parameters
        ----------
        path : str or os.PathLike
            The file, ending in .html or .htm.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        path = Path(path)
        if path.suffix.lower() not in (".html", ".htm"):
            raise InvalidInputError(f"{path}: the view is a web page; give a file name ending in .html")
        path.write_text(self.html, encoding="utf-8")
        return path

    def __repr__(self) -> str:
        return f"<cgaskin View: {len(self.html) / 1e6:.1f} MB page; save(path) or display it in a notebook>"


def show(rig, pose=None, clip=None, *, play=None, time: float = 0.0, height: int = 480,
         skinning: str = "cgaskin") -> View:
    """The viewer for a rig: plays its clips (timeline, speed, loop), orbits, shows the skeleton with
    bone names, weights by joint, a live dilation of a joint, the open edges (cut rims, slits,
    holes), and saves PNGs.

    Parameters
    ----------
    rig : Rig or str or os.PathLike
        The model, or a model file.
    pose : Pose, optional
        A pose of the rig to show (held by an extra clip "pose" of two equal keys, selected and
        paused; the rig's own clips stay in the clip menu).
    clip : str or int, optional
        The clip to start with (default: the first); not with ``pose``.
    play : bool, optional
        Start playing (default: yes for a clip, no for a pose).
    time : float, optional
        Seconds into the clip to start at.
    height : int, optional
        The notebook iframe's height in pixels, >= 100.
    skinning : {"cgaskin", "three"}, optional
        The bones' versors (cgaskin's generated GLSL ES in the vertex shader) or three.js's matrix
        skinning to start with; the page switches between them.

    Returns
    -------
    View

    Examples
    --------
    >>> view = cgaskin.view.show(cgaskin.capsule_arm(), clip="wave", time=0.5)
    >>> view.save("arm.html")
    PosixPath('arm.html')
    """
    if not isinstance(height, int) or height < 100:
        raise InvalidInputError(f"height {height!r}: give whole pixels >= 100")
    return View(view_html(rig, clip=clip, pose=pose, play=play, time=time, skinning=skinning), height=height)
