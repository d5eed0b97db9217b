"""FBX, Collada and every other format assimp reads, through the ``assimp`` command line.

``cgaskin.load`` sends every extension but .glb/.gltf here; assimp decides what it can read
(``assimp_formats()``: what ``assimp listext`` prints), and its "cannot read" becomes the
``ModelFormatError``. Static formats (OBJ, PLY, STL, ...) convert to a glTF without a skin, which
the glTF loader reads as rigid bones at the rest positions.

Why the command line and not a Python binding: PyPI ``pyassimp`` 5.2.5 declares the ``aiBone`` struct
of assimp 5.0, without the ``mArmature``/``mNode`` fields that libassimp >= 5.1 has, so reading any
bone through it fails ("NULL pointer access") against Debian's libassimp5 5.2.5. The ``assimp`` tool
(Debian package ``assimp-utils``) is built against the matching library, so we let it convert the file
to binary glTF 2.0 in a temporary folder and read that with our own glTF loader.

What the conversion does (assimp 5.2.5, checked on the shipped models):

* ``assimp export`` applies no import post-processing unless asked; the glTF 2.0 exporter then
  enforces ``JoinIdenticalVertices | Triangulate | SortByPType``. FBX import is unindexed (3 vertices
  per face), so the join is what welds identical vertices (Arm5: 15111 -> 2935 vertices).
  Asking for a preset (``-cfull`` etc.) makes it worse: the join then runs at import, the exporter
  re-expands the scene to unindexed form and does not join again (Arm5 stays at 15111 vertices).
* Faces, bones, inverse bind matrices and the node hierarchy (including assimp's ``$AssimpFbx$``
  pivot nodes) are kept. The glTF exporter writes only the *first* 4 influences of a vertex, in file
  order, dropping the rest even when they weigh more; ``-lbw`` (LimitBoneWeights, the one
  post-processing step asked for, which leaves the vertex count alone) first keeps the 4 largest
  and renormalises them, as cgaskin does for glTF files, and cgaskin warns as it does for glTF
  files (``_assimp_influences``: -lbw itself is silent). Weights that still do not sum to 1 are
  renormalised by the glTF loader.
* The ``.glb`` files shipped beside each ``.fbx`` in the models folder are exactly this conversion;
  their accessors are byte-identical to a fresh one (only unused padding between buffer views can
  differ: assimp leaves it uninitialised).
"""
from __future__ import annotations

import os
import pathlib
import re
import shutil
import subprocess
import tempfile
import warnings
from dataclasses import replace

from .._shared.warn import warn
from ..animation.rig import Rig
from ..errors import ModelFormatError
from ._assimp_dump import assxml_dump
from ._assimp_influences import removed_weights, warn_about_dropped_influences
from ._assimp_ticks import repair_key_times
from ._model_file import check_model_file

__all__ = ["load_assimp", "assimp_executable", "assimp_formats", "DEFAULT_TIMEOUT_S"]

#: Seconds a conversion may take. Arm5.fbx (2.5 MB, 5037 faces) converts in ~0.1 s; the limit only
#: guards against a hang on a hostile file.
DEFAULT_TIMEOUT_S = 120.0

_INSTALL_HINT = ("the `assimp` command line tool is needed to read FBX/DAE and other non-glTF formats; "
                 "install it with `apt-get install assimp-utils` (Debian/Ubuntu) or put `assimp` on PATH")


def assimp_executable() -> str:
    """Path of the ``assimp`` command line tool; ModelFormatError with install advice when missing."""
    exe = shutil.which("assimp")
    if exe is None:
        raise ModelFormatError(_INSTALL_HINT)
    return exe


_FORMATS: dict[str, tuple[str, ...]] = {}     # executable -> what its listext printed (answers only)


def assimp_formats(executable: str | None = None) -> tuple[str, ...]:
    """The extensions (".fbx", ".dae", ...) the installed ``assimp`` reads, as ``assimp listext``
    prints them; () when the tool is missing or does not answer."""
    exe = executable or shutil.which("assimp")
    if not exe:
        return ()
    if exe not in _FORMATS:
        try:
            proc = subprocess.run([exe, "listext"], stdin=subprocess.DEVNULL, capture_output=True,
                                  text=True, errors="replace", timeout=30, check=False)
        except (OSError, subprocess.SubprocessError):
            return ()
        found = re.findall(r"\*\.([A-Za-z0-9_.]+)", proc.stdout) if proc.returncode == 0 else []
        if not found:
            return ()
        _FORMATS[exe] = tuple(dict.fromkeys("." + e.lower() for e in found))
    return _FORMATS[exe]


def _cannot_read(src: pathlib.Path, exe: str, returncode: int, output: str) -> ModelFormatError:
    """assimp's "cannot read", saying how cgaskin reads models and what this assimp knows."""
    known = [e for e in assimp_formats(exe) if e not in (".glb", ".gltf")]
    formats = f"; this assimp reads {' '.join(known)}" if known else ""
    return ModelFormatError(f"{src}: assimp cannot read this file (exit status {returncode}): "
                            f"{_failure_text(output)} (cgaskin reads glTF, .glb and .gltf, natively "
                            f"and every other format through assimp{formats})")


def _failure_text(output: str) -> str:
    """The lines of assimp's output that say what went wrong (it prints errors to stdout)."""
    lines = [ln.strip() for ln in output.splitlines() if ln.strip()]
    errors = [ln for ln in lines if "ERROR" in ln.upper() or "EXCEPTION" in ln.upper()]
    return "; ".join(errors or lines[-5:]) or "no output"


def load_assimp(path, *, timeout: float = DEFAULT_TIMEOUT_S, executable: str | None = None) -> Rig:
    """Load a model in any format assimp reads (FBX, DAE, OBJ, PLY, STL, ...) as a ``Rig``.

    The file is converted with ``assimp export <path> <tmp>/<stem>.glb -fglb2 -lbw -l`` (no other
    post-processing; see the module docstring for what assimp does) and read by
    ``cgaskin.rigs.gltf.load_gltf`` (meshes without a skin become rigid bones, see there).

    path : str or os.PathLike
    timeout : float seconds allowed for the conversion
    executable : path of the ``assimp`` tool; default: the one on PATH

    returns Rig named after the file's stem

    Raises ModelFormatError when the file is missing, assimp cannot read it, the conversion times
    out, or the ``assimp`` tool is not installed; NoSkinError when it holds no mesh.
    """
    src = pathlib.Path(os.fspath(path))
    check_model_file(src, empty_ok=True)  # missing, a directory, a device (/dev/null), a pipe
    exe = executable or assimp_executable()
    src = src.resolve()   # absolute: a name starting with '-' must not read as an option

    with tempfile.TemporaryDirectory(prefix="cgaskin-assimp-") as tmp:
        out = pathlib.Path(tmp) / f"{src.stem or 'model'}.glb"
        # -l: assimp's log says how many weights -lbw removed (see _assimp_influences)
        cmd = [exe, "export", str(src), str(out), "-fglb2", "-lbw", "-l"]
        try:
            # cwd=tmp: whatever else the tool writes (logs, extracted textures) goes away with tmp.
            proc = subprocess.run(cmd, cwd=tmp, stdin=subprocess.DEVNULL, capture_output=True,
                                  text=True, errors="replace", timeout=timeout, check=False)
        except FileNotFoundError:
            raise ModelFormatError(f"{exe}: not found; {_INSTALL_HINT}") from None
        except subprocess.TimeoutExpired:
            raise ModelFormatError(f"{src}: assimp did not finish converting within {timeout:g} s") from None
        if proc.returncode != 0 or not out.is_file() or out.stat().st_size == 0:
            raise _cannot_read(src, exe, proc.returncode, proc.stdout + "\n" + proc.stderr)
        removed = removed_weights(proc.stdout + proc.stderr)
        if removed:  # the warning glTF files with more than 4 influences get
            warn_about_dropped_influences(exe, src, pathlib.Path(tmp), timeout, removed)
        rig, caught = _read_converted(out, src)
        if any(_UNTIMED in str(w.message) for w in caught) and repair_key_times(
                out, assxml_dump(exe, src, pathlib.Path(tmp), timeout), src.name):
            rig, caught = _read_converted(out, src)   # with the times of 0-ticks-per-second clips
        for w in caught:
            message = str(w.message).replace(str(out), str(src)).replace(out.name, src.name)
            if _UNTIMED in message:  # a clip dropped all the same: say where its times came from
                message += (" (assimp converts the keys of an animation whose ticks per second are 0 "
                            "or missing to non-finite times; set them in the source)")
            warn(message, w.category)
    return replace(rig, name=src.stem)


#: what the glTF loader's warning about a clip dropped for non-finite key times says
_UNTIMED = "key times hold non-finite values"


def _read_converted(out: pathlib.Path, src: pathlib.Path):
    """(rig, warnings) of assimp's conversion ``out`` of ``src``: the glTF loader names the file it
    read, so its warnings are recorded (the caller re-issues them naming the user's file) and its
    errors re-raised naming ``src``."""
    from .gltf import load_gltf   # imported here: gltf.py imports nothing of this module
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rig = load_gltf(out)
    except ModelFormatError as exc:
        # Same error class (NoSkinError stays NoSkinError), naming the user's file, not our tmp one.
        message = str(exc)
        where = f"{src} (converted by assimp)"
        message = message.replace(str(out), where) if str(out) in message else message.replace(out.name, where)
        raise type(exc)(message) from exc
    return rig, caught
