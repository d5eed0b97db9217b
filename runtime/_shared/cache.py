"""Values derived from a rig (its welded topology, checked arrays, BVH), kept while the rig lives.

Rigs are frozen and compared by identity (``eq=False``), so they are weak dictionary keys: an entry
goes with its rig. An entry also remembers the rig's ``vertices`` and ``faces`` objects and is
rebuilt when either is another object. A rig's arrays are read-only (``frozen.py``), so no edit in
place can leave an entry stale; numpy lets a caller set such an array writeable again (the buffer
behind it is), and then an operation refuses the rig (``check_read_only``) rather than use values
derived from arrays that may have changed.
"""
from __future__ import annotations

import weakref

from ..errors import InvalidInputError

__all__ = ["rig_cached", "clear", "check_read_only"]

#: the arrays of a rig that operations read (each is read-only unless a caller made it writeable)
_ARRAYS = ("vertices", "faces", "joints", "weights")


def check_read_only(rig) -> None:
    """Raise ``InvalidInputError`` when one of ``rig``'s arrays was made writeable again."""
    for name in _ARRAYS:
        if getattr(rig, name).flags.writeable:
            raise InvalidInputError(f"rig.{name} was made writeable again: a rig's arrays are read-only, as what "
                                    "is derived from them (topology, BVH) is kept per rig; make a new rig with "
                                    "rig.with_mesh(vertices, faces, joints, weights) instead")

#: rig -> (its vertices object, its faces object, {name: value})
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def rig_cached(rig, name: str, build):
    """``build(rig)``, computed once per rig and name and kept while the rig lives."""
    check_read_only(rig)
    entry = _CACHE.get(rig)
    if entry is None or entry[0] is not rig.vertices or entry[1] is not rig.faces:
        entry = (rig.vertices, rig.faces, {})
        try:
            _CACHE[rig] = entry
        except TypeError:                 # not weak-referenceable: nothing is cached
            return build(rig)
    values = entry[2]
    if name not in values:
        values[name] = build(rig)
    return values[name]


def clear() -> None:
    """Forget everything cached for every rig."""
    _CACHE.clear()


def seed(rig, name: str, value) -> None:
    """Store ``value`` as ``rig``'s cached ``name`` (an operation that made ``rig`` from another one
    and knows it already, e.g. the boundary of a torn rig, which only the stroke's patch changed)."""
    rig_cached(rig, name, lambda _rig: value)
