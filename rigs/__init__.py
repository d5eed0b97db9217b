"""Model I/O: load any supported file as a ``Rig``, save a ``Rig`` as skinned glTF 2.0.

glTF (.glb, .gltf) is read natively (``cgaskin.rigs.gltf``); other formats go through assimp
(``cgaskin.rigs.assimp``, imported only when needed).
"""
from __future__ import annotations

import os
from pathlib import Path

from ..animation.rig import Rig
from ..errors import InvalidInputError, ModelFormatError

GLTF_EXTENSIONS = (".glb", ".gltf")
#: formats read through assimp; assimp knows more, these are the ones cgaskin is checked on
ASSIMP_EXTENSIONS = (".fbx", ".dae", ".obj", ".blend", ".3ds", ".x", ".ms3d", ".md5mesh", ".smd",
                     ".ply", ".stl")
SAVE_EXTENSIONS = GLTF_EXTENSIONS

__all__ = ["load", "save", "GLTF_EXTENSIONS", "ASSIMP_EXTENSIONS", "SAVE_EXTENSIONS"]


def _path(value, name: str) -> Path:
    if not isinstance(value, (str, os.PathLike)):
        raise InvalidInputError(f"{name} must be a file path (str or os.PathLike), got "
                                f"{type(value).__name__}")
    return Path(value)


def load(path, **options):
    """Load a rigged model as a ``Rig``, picking the reader by file extension.

    Parameters
    ----------
    path : str or os.PathLike
        .glb / .gltf (native reader) or a format assimp reads (.fbx, .dae, ...).
    **options
        Passed to the reader (the glTF reader takes none).

    Raises
    ------
    ModelFormatError
        Unknown extension (the message lists the supported ones), or a malformed file.
    NoSkinError
        The file holds no skinned mesh.
    """
    path = _path(path, "path")
    suffix = path.suffix.lower()
    if suffix in GLTF_EXTENSIONS:
        from .gltf import load_gltf
        if options:
            raise TypeError(f"load_gltf takes no options, got {', '.join(sorted(options))}")
        return load_gltf(path)
    if suffix in ASSIMP_EXTENSIONS:
        from .assimp import load_assimp  # lazy: needs the assimp library or command line
        return load_assimp(path, **options)
    raise ModelFormatError(
        f"{path.name}: unknown model format {suffix or '(no extension)'!r}; cgaskin reads "
        f"{', '.join(GLTF_EXTENSIONS + ASSIMP_EXTENSIONS)}")


def save(rig, path):
    """Save ``rig`` as skinned glTF 2.0 (.glb or .gltf), clips included; returns the path.

    Raises
    ------
    ModelFormatError
        The extension is not .glb or .gltf.
    """
    if not isinstance(rig, Rig):
        raise InvalidInputError(f"rig must be a cgaskin.Rig, got {type(rig).__name__}")
    path = _path(path, "path")
    if path.suffix.lower() not in SAVE_EXTENSIONS:
        raise ModelFormatError(f"cannot save {path.name}: cgaskin writes {', '.join(SAVE_EXTENSIONS)} "
                               f"(skinned glTF 2.0)")
    from .export import save_gltf
    return save_gltf(rig, path)
