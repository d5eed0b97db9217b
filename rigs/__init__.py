"""Model I/O: load any supported file as a ``Rig``, save a ``Rig`` as skinned glTF 2.0.

glTF (.glb, .gltf) is read natively (``cgaskin.rigs.gltf``); every other extension goes to assimp
(``cgaskin.rigs.assimp``, imported only when needed), which decides whether it can read the file
(``assimp listext`` prints what the installed one knows: FBX, Collada, OBJ, PLY, STL, 3DS, ...).
Models with or without a skin load alike: a mesh without a skin becomes a rigid bone.
"""
from __future__ import annotations

import os
from pathlib import Path

from ..animation.rig import Rig
from ..errors import InvalidInputError, ModelFormatError
from ._model_file import check_model_file

GLTF_EXTENSIONS = (".glb", ".gltf")
SAVE_EXTENSIONS = GLTF_EXTENSIONS

__all__ = ["load", "save", "GLTF_EXTENSIONS", "SAVE_EXTENSIONS"]


def _path(value, name: str) -> Path:
    if not isinstance(value, (str, os.PathLike)):
        raise InvalidInputError(f"{name} must be a file path (str or os.PathLike), got "
                                f"{type(value).__name__}")
    return Path(value)


def load(path, **options):
    """Load a model, skinned or not, as a ``Rig``, picking the reader by file extension.

    .glb / .gltf are read natively; every other extension is converted by assimp (FBX, Collada,
    .zae, IQM, MS3D, OBJ, PLY, STL, 3DS, ... whatever the installed ``assimp`` reads) and then read
    as glTF. Mesh nodes without a skin (static formats such as OBJ/PLY/STL, props, scans) load as
    rigid bones at their rest positions (see ``cgaskin.rigs.gltf.load_gltf``), so they pose, cut and
    tear like any skinned model.

    Parameters
    ----------
    path : str or os.PathLike
    **options
        Passed to the reader (the glTF reader takes none; assimp: ``timeout``, ``executable``).

    Raises
    ------
    ModelFormatError
        A malformed file, or one assimp cannot read (the message names the file and the formats
        the installed assimp knows), or a non-glTF file without the ``assimp`` tool installed.
    NoSkinError
        The file holds no mesh.
    """
    path = _path(path, "path")
    suffix = path.suffix.lower()
    # what the path is when it is no model file: missing, /dev/null, a pipe, ...
    check_model_file(path, empty_ok=suffix not in GLTF_EXTENSIONS)
    if suffix in GLTF_EXTENSIONS:
        from .gltf import load_gltf
        if options:
            raise TypeError(f"load_gltf takes no options, got {', '.join(sorted(options))}")
        return load_gltf(path)
    from .assimp import load_assimp  # lazy: needs the assimp command line
    return load_assimp(path, **options)


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
