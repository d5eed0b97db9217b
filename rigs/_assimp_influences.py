"""How many bone influences assimp's conversion dropped, for the warning glTF files get.

``assimp export -lbw`` (LimitBoneWeights) keeps the 4 largest weights of each vertex and
renormalises them, as ``check_mesh`` does for glTF files, but silently: the glTF it writes holds 4
influences at most, so the loader cannot see that more were there. Its log (``-l``) says how many
weights it removed ("Removed 12 weights. Input bones: 6. Output bones: 4"); when it removed any,
assimp's XML dump of the source (``_assimp_dump``: every weight of every bone) tells the vertices
that had more than 4 and the most any had, and ``warn_dropped_influences`` gives the glTF files'
warning.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._shared.warn import warn
from ..animation.validate import MAX_INFLUENCES, warn_dropped_influences
from ..errors import ModelWarning
from ._assimp_dump import assxml_dump

__all__ = ["removed_weights", "warn_about_dropped_influences"]

_REMOVED = re.compile(r"Removed (\d+) weights")
_MESH = re.compile(r"<Mesh[\s>]")
_WEIGHT = re.compile(r'<Weight index="(\d+)"')


def removed_weights(log: str) -> int:
    """The number of weights LimitBoneWeights removed, summed over the meshes, from assimp's log."""
    return sum(int(n) for n in _REMOVED.findall(log))


def influence_counts(assxml: str) -> list[np.ndarray]:
    """Per mesh of an assxml dump, the number of bone weights of each weighted vertex."""
    counts = []
    for mesh in _MESH.split(assxml)[1:]:
        ids = np.array(_WEIGHT.findall(mesh), dtype=np.int64)
        counts.append(np.bincount(ids) if len(ids) else np.zeros(0, dtype=np.int64))
    return counts


def warn_about_dropped_influences(exe: str, src: Path, tmp: Path, timeout: float, removed: int) -> None:
    """Warn (naming ``src``) about the vertices of ``src`` that had more than 4 influences, of
    which assimp ``removed`` weights (when the dump fails, the warning says just that)."""
    text = assxml_dump(exe, src, tmp, timeout)
    counts = np.concatenate(influence_counts(text) or [np.zeros(0, dtype=np.int64)])
    over = counts[counts > MAX_INFLUENCES]
    if len(over):
        warn_dropped_influences(src.name, len(over), int(over.max()))
    else:
        warn(f"{src.name}: assimp removed {removed} bone weights of vertices with more than "
             f"{MAX_INFLUENCES} influences; kept the {MAX_INFLUENCES} largest weights of each and "
             f"renormalised", ModelWarning)
