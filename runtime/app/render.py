"""Headless pictures of meshes (matplotlib, the optional ``render`` extra)."""
from __future__ import annotations

import numpy as np

from ..errors import CgaskinError


def _pyplot():
    try:
        import matplotlib
    except ImportError:
        raise CgaskinError("pictures need matplotlib: pip install 'cgaskin[render]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _shade(tris, light=np.array([0.3, -0.5, 0.8])):
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = light / np.linalg.norm(light)
    return 0.35 + 0.65 * np.abs(n @ light)


def render_strip(frames, path, titles=None, elev=65.0, azim=-90.0, size=4.0, columns=3) -> None:
    """Save a PNG with one 3D view per frame, ``columns`` per row, all at one scale.

    frames : list of (vertices (n, 3), faces (m, 3) int[, marked faces (m,) bool, drawn blue])
    """
    plt = _pyplot()
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    all_points = np.concatenate([f[0] for f in frames])
    lo, hi = all_points.min(0), all_points.max(0)
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2 * 0.75
    columns = min(columns, len(frames))
    rows = -(-len(frames) // columns)
    fig = plt.figure(figsize=(size * columns, size * rows))
    for i, frame in enumerate(frames):
        vertices, faces = frame[0], frame[1]
        ax = fig.add_subplot(rows, columns, i + 1, projection="3d")
        tris = vertices[faces]
        shade = _shade(tris)
        base = np.array([0.85, 0.55, 0.45])
        colours = np.clip(shade[:, None] * base, 0, 1)
        if len(frame) > 2:                                 # highlight marked faces
            colours[frame[2] > 0] = np.clip(shade[frame[2] > 0, None] * np.array([0.3, 0.5, 0.9]), 0, 1)
        ax.add_collection3d(Poly3DCollection(tris, facecolors=colours, edgecolors="none"))
        for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
            setter(c - half, c + half)
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
        if titles:
            ax.set_title(titles[i], fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
