"""One way to write a file whole: into a temporary file beside it, then renamed over it.

``os.replace`` within one folder is atomic: a reader, or a process killed half-way, sees the old
file or the new one, never a part of either. The batch writes its manifest and every item's files so.
"""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["replaced", "TEMPORARY"]

#: what a temporary file's name holds before its suffix: ``<stem>.<pid>.tmp<suffix>`` (the suffix
#: kept: a writer may choose its format by it); ``f"*{TEMPORARY}{suffix}"`` finds those a killed
#: process left
TEMPORARY = ".tmp"


@contextlib.contextmanager
def replaced(path):
    """Yield a temporary path beside ``path`` to write; when the block ends without error it replaces
    ``path``; on an error (or an interrupt) it is removed and ``path`` stays as it was."""
    path = Path(path)
    temporary = path.with_name(f"{path.stem}.{os.getpid()}{TEMPORARY}{path.suffix}")
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
