"""Reading a glTF file: .gltf JSON or .glb container (spec 4.4) -> ``_GltfFile``.

The two are told apart by content, not by extension. The JSON is checked for the glTF version and
for required extensions that change how geometry is stored before pygltflib parses it.
"""
from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import pygltflib

from ..errors import ModelFormatError
from ._gltf_constants import GLB_BIN_CHUNK, GLB_JSON_CHUNK, GLB_MAGIC, UNSUPPORTED_EXTENSIONS
from ._gltf_document import _GltfFile
from ._model_file import check_model_file


# --- reading the container --------------------------------------------------------------------

def _read_document(path: Path) -> _GltfFile:
    """Read a .gltf or .glb file (told apart by content, not by extension)."""
    name = path.name
    check_model_file(path)  # missing, a directory, a device (/dev/null), a pipe, empty
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ModelFormatError(f"{name}: cannot read the file: {exc}") from None

    glb_bin = None
    if data[:4] == GLB_MAGIC:
        json_bytes, glb_bin = _split_glb(name, data)
    else:
        if len(data) == 0:
            raise ModelFormatError(f"{name}: the file is empty")
        json_bytes = data
    try:
        text = json_bytes.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ModelFormatError(f"{name}: the glTF JSON is not valid UTF-8 ({exc}); the file is "
                               f"corrupt or not a glTF file") from None
    try:
        raw = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFormatError(f"{name}: the glTF JSON is malformed: {exc}") from None
    except RecursionError:
        # json's decoder recurses once per nested array/object: a file nested thousands deep is
        # no glTF (its documents nest a few levels, extras a few more), whatever else it is
        raise ModelFormatError(f"{name}: the glTF JSON nests arrays/objects deeper than Python's "
                               f"parser can follow ({sys.getrecursionlimit()} levels); the file is "
                               f"corrupt or not a glTF file") from None
    if not isinstance(raw, dict):
        raise ModelFormatError(f"{name}: the glTF JSON must be an object, got {type(raw).__name__}")
    version = raw.get("asset", {}).get("version") if isinstance(raw.get("asset"), dict) else None
    if isinstance(version, str) and not version.startswith("2"):
        raise ModelFormatError(f"{name}: glTF version {version} is not supported (only 2.x); "
                               f"convert the file to glTF 2.0")
    required = raw.get("extensionsRequired") or []
    if isinstance(required, list):
        missing = sorted(set(map(str, required)) & UNSUPPORTED_EXTENSIONS)
        if missing:
            raise ModelFormatError(f"{name}: the file requires {', '.join(missing)}, which cgaskin "
                                   f"cannot decode; re-export it without mesh compression")
    try:
        doc = pygltflib.GLTF2.from_json(json.dumps(raw))
    except Exception as exc:  # dataclasses_json raises whatever a wrongly typed property triggers
        raise ModelFormatError(f"{name}: not a valid glTF document: a property has the wrong JSON "
                               f"type ({type(exc).__name__}: {exc})") from None
    return _GltfFile(path, doc, glb_bin)


def _split_glb(name: str, data: bytes):
    """(JSON chunk bytes, BIN chunk bytes or None) of a GLB container (spec 4.4)."""
    if len(data) < 12:
        raise ModelFormatError(f"{name}: truncated GLB: {len(data)} bytes, less than the 12-byte header")
    _, version, length = struct.unpack_from("<4sII", data, 0)
    if version != 2:
        raise ModelFormatError(f"{name}: GLB container version {version} is not supported (only 2)")
    if length > len(data):
        raise ModelFormatError(f"{name}: truncated GLB: the header announces {length} bytes but the "
                               f"file has {len(data)}")
    chunks = []
    offset = 12
    while offset < length:
        if offset + 8 > length:
            raise ModelFormatError(f"{name}: truncated GLB: chunk header at byte {offset} runs past "
                                   f"the end ({length} bytes)")
        chunk_length, chunk_type = struct.unpack_from("<II", data, offset)
        start, end = offset + 8, offset + 8 + chunk_length
        if end > length:
            raise ModelFormatError(f"{name}: truncated GLB: chunk at byte {offset} declares "
                                   f"{chunk_length} bytes, only {length - start} remain")
        chunks.append((chunk_type, data[start:end]))
        offset = end
    if not chunks or chunks[0][0] != GLB_JSON_CHUNK:
        raise ModelFormatError(f"{name}: malformed GLB: the first chunk must be the JSON chunk")
    json_bytes = chunks[0][1].rstrip(b" \x00\t\r\n")  # the spec pads JSON with spaces
    bins = [payload for ctype, payload in chunks[1:] if ctype == GLB_BIN_CHUNK]
    return json_bytes, (bins[0] if bins else None)
