"""assimp's own XML dump of a source file (``assimp export SRC X.assxml -fassxml -jiv``).

The glTF that ``load_assimp`` reads is what assimp's glTF exporter makes of the source, which
loses two things: the bone weights beyond 4 per vertex (``_assimp_influences``) and the key times
of animations whose ticks per second are 0 (``_assimp_ticks``). The assxml dump keeps both: every
weight of every bone, every key at its time in ticks. Vertices are joined (``-jiv``) as the glTF
exporter joins them, so that vertex counts agree. The dump is made at most once per conversion.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

__all__ = ["assxml_dump"]


def assxml_dump(exe: str, src: Path, tmp: Path, timeout: float) -> str:
    """The assxml text of ``src`` (written into the folder ``tmp`` once, then reused); "" when
    assimp cannot dump it."""
    dump = tmp / "source.assxml"
    if not dump.is_file():
        try:
            subprocess.run([exe, "export", str(src), str(dump), "-fassxml", "-jiv"], cwd=tmp,
                           stdin=subprocess.DEVNULL, capture_output=True, timeout=timeout, check=False)
        except (OSError, subprocess.SubprocessError):
            return ""
    try:
        return dump.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
