"""One batch run per folder: a lock file in the batch folder, held while the run lasts.

A run sweeps the temporary files a killed run left in its folder before it starts; a second run on
the same folder would sweep the first one's files in flight (and both would rewrite the manifest).
So ``run`` holds ``DIR/.cgaskin-batch.lock`` locked (``flock``; ``msvcrt.locking`` on Windows): a second
run gets ``FolderInUseError`` naming the process that holds it. The operating system drops the lock
of a process that dies, however it dies: a killed run's lock file is stale, never in the way.

The file is removed when the run ends. Unlinking a locked file races with a process that opened it
just before: that one would then hold a lock on a file no longer in the folder, while a third makes
a new one. A taker therefore checks, once it holds the lock, that the path still names the file it
locked, and takes it again otherwise.
"""
from __future__ import annotations

import contextlib
import os
from pathlib import Path

from ..errors import FolderInUseError

try:
    import fcntl
except ImportError:                  # pragma: no cover (Windows)
    fcntl = None
    import msvcrt

__all__ = ["folder_lock", "LOCK_NAME"]

#: the lock file's name in the batch folder
LOCK_NAME = ".cgaskin-batch.lock"


def _try_lock(fd: int) -> bool:
    try:
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        else:                        # pragma: no cover
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError:
        return False
    return True


def _holder(fd: int) -> str:
    """Who holds the lock, as its file says (the process id it wrote)."""
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        text = os.read(fd, 64).decode("ascii", "replace").strip()
    except OSError:                  # (Windows: the locked byte cannot be read)
        text = ""
    return f"process {text}" if text.isdigit() else "another process"


@contextlib.contextmanager
def folder_lock(folder):
    """Hold ``folder``'s batch lock while the block runs (``folder`` exists); ``FolderInUseError`` when
    another process holds it."""
    path = Path(folder) / LOCK_NAME
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        if not _try_lock(fd):
            holder = _holder(fd)
            os.close(fd)
            raise FolderInUseError(f"{folder}: {holder} is running a batch on this folder (it holds {path}); "
                                   f"wait for it to end, or give another --out folder")
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:    # removed by the run that held it just before
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, str(os.getpid()).encode("ascii"))
        yield path
    finally:
        with contextlib.suppress(OSError):
            path.unlink()            # (still locked: a taker that opened it now finds it gone, above)
        os.close(fd)
