"""What a model path names, checked before any reader opens it.

Every reader (glTF natively, the rest through assimp) needs a regular, non-empty file. Anything
else is refused up front with a message that says what the path is: reading ``/dev/zero`` or a
named pipe would block forever, and "no such file" for ``/dev/null`` (which exists) misleads.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

from ..errors import ModelFormatError

__all__ = ["check_model_file"]

#: what ``stat`` calls the kinds of file that are no regular file (a directory is reported apart)
_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISSOCK, "a socket"))


def check_model_file(path: Path, empty_ok: bool = False) -> None:
    """Raise ``ModelFormatError`` unless ``path`` is a regular file holding at least one byte
    (any regular file with ``empty_ok``: assimp says itself why it cannot read an empty one).

    The message names the file and what it is instead: missing, a directory, a device, a pipe,
    a socket, empty, or unreadable.
    """
    name = path.name or str(path)
    try:
        info = os.stat(path)  # follows symlinks: a link to a model is a model
    except FileNotFoundError:
        raise ModelFormatError(f"{name}: no such file ({path})") from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL character in the path
        raise ModelFormatError(f"{name}: cannot read the file: {exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise ModelFormatError(f"{name}: is a directory, not a model file ({path})")
    if not stat.S_ISREG(info.st_mode):
        kind = next((text for test, text in _KINDS if test(info.st_mode)), "a special file")
        raise ModelFormatError(f"{name}: is not a regular file but {kind} ({path}); cgaskin reads "
                               f"models from regular files (.glb, .gltf, or a format assimp reads)")
    if info.st_size == 0 and not empty_ok:
        raise ModelFormatError(f"{name}: the file is empty ({path}); it holds no model")
