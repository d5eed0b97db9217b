"""One parsed glTF document with checked access to it (spec 3.6 "Binary data storage").

``_GltfFile`` holds the pygltflib document and the GLB binary chunk, and gives typed, range-checked
access to the JSON (``items``, ``index``, ``get``, ``count``, ``floats``), to buffers (GLB chunk,
``data:`` URIs, files in the folder of the .gltf or below it: ``external_file`` refuses any URI
that leads outside it) and to decoded accessors (every component type, ``normalized``,
``byteStride``, matrix column padding, sparse, no bufferView). Every problem is a
``ModelFormatError`` naming the file; ``warn`` attributes warnings to the first caller outside
cgaskin.
"""
from __future__ import annotations

import base64
import binascii
import os
import re
import urllib.parse
from pathlib import Path

import numpy as np
import pygltflib

from .._shared.warn import warn
from ..errors import ModelFormatError, ModelWarning
from ._gltf_constants import (COMPONENT_DTYPES, COMPONENT_NAMES, INTEGER_INDEX_TYPES,
                              MAX_BUFFERLESS_COMPONENTS, NORMALIZED_DIVISORS, TYPE_SHAPES)


#: a URI scheme (RFC 3986 section 3.1: ``file:``, ``http:``, also ``C:``): not a relative reference
_URI_SCHEME = re.compile(r"[A-Za-z][A-Za-z0-9+.-]*:")


# --- file-level context ---------------------------------------------------------------------------

class _GltfFile:
    """One parsed file: its document, its buffers, and checked access to both."""

    def __init__(self, path: Path, doc: pygltflib.GLTF2, glb_bin: bytes | None):
        self.path = path
        self.doc = doc
        self.glb_bin = glb_bin
        self._buffers: dict[int, bytes] = {}
        self._accessors: dict[int, np.ndarray] = {}

    # -- messages --
    def error(self, message: str, cls=ModelFormatError) -> ModelFormatError:
        return cls(f"{self.path.name}: {message}")

    def warn(self, message: str, prefix: bool = True) -> None:
        """Warn, attributing the warning to the first caller outside cgaskin."""
        warn(f"{self.path.name}: {message}" if prefix else message, ModelWarning)

    # -- typed access to the JSON (pygltflib does not check types) --
    def items(self, name: str) -> list:
        value = getattr(self.doc, name, None)
        if value is None:
            return []
        if not isinstance(value, list):
            raise self.error(f"'{name}' must be a JSON array, got {type(value).__name__}")
        return value

    def index(self, value, collection: str, what: str) -> int:
        """Check that ``value`` indexes the top-level array ``collection``."""
        n = len(self.items(collection))
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(f"{what} must be an index into '{collection}', got {value!r}")
        if not 0 <= value < n:
            raise self.error(f"{what} = {value} is out of range: the file has {n} {collection}")
        return value

    def get(self, collection: str, value, what: str):
        return self.items(collection)[self.index(value, collection, what)]

    def count(self, value, what: str, minimum: int = 0) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise self.error(f"{what} must be an integer >= {minimum}, got {value!r}")
        return value

    def floats(self, value, length: int, what: str) -> np.ndarray:
        try:
            array = np.array(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise self.error(f"{what} must be a list of {length} numbers, got {value!r}") from None
        if array.shape != (length,):
            raise self.error(f"{what} must be a list of {length} numbers, got {value!r}")
        if not np.isfinite(array).all():
            raise self.error(f"{what} holds non-finite values {array.tolist()}")
        return array

    # -- external resources (glTF 2.0: a URI is a relative reference or a data: URI) --
    def external_file(self, uri: str, what: str) -> Path:
        """The file an external (not ``data:``) ``uri`` names, resolved, symlinks included.

        Refuses, naming the URI and the rule, every URI that is not a relative reference (a
        scheme such as ``file:`` or ``http:``, a network path ``//host/...``, an absolute path,
        percent-encoded or not) and every one that resolves outside the folder of the .gltf
        (``..``, a symlink in the folder pointing out of it). The folder is the one the model was
        opened from, itself resolved. The caller reads the returned path, which holds no symlink.
        """
        rule = "external resources must lie in the model's folder or below it"
        if _URI_SCHEME.match(uri) or uri.startswith("//"):
            raise self.error(f"{what} refers to {uri!r}, which is not a relative URI: {rule} "
                             f"and be referred to by relative URIs, or be embedded as data: URIs; "
                             f"download or copy the file into the model's folder and refer to it "
                             f"by its relative path")
        relative = urllib.parse.unquote(uri)
        if "\0" in relative:
            raise self.error(f"{what} uri {uri!r} holds a NUL character: it names no file")
        if os.path.isabs(relative):
            raise self.error(f"{what} refers to the absolute path {uri!r}: {rule}; copy the "
                             f"file into the model's folder and refer to it by its relative path")
        try:
            folder = self.path.parent.resolve()
            file = (folder / relative).resolve()
        except (OSError, RuntimeError) as exc:  # RuntimeError: a symlink loop (Python < 3.13)
            raise self.error(f"{what} uri {uri!r} cannot be resolved ({exc}); {rule}") from None
        if not file.is_relative_to(folder):
            raise self.error(f"{what} refers to {uri!r}, which resolves to {file}, outside the "
                             f"model's folder {folder}: {rule}; copy the file into that folder and "
                             f"refer to it by its relative path")
        return file

    # -- buffers (spec 3.6.1) --
    def buffer(self, i: int) -> bytes:
        if i in self._buffers:
            return self._buffers[i]
        buf = self.get("buffers", i, f"buffer index {i}")
        declared = self.count(buf.byteLength, f"buffer {i} byteLength", minimum=1)
        uri = buf.uri
        if uri is None:
            # only the first buffer of a GLB may omit its uri: it is the binary chunk
            if i != 0 or self.glb_bin is None:
                raise self.error(f"buffer {i} has no uri and the file has no GLB binary chunk for it")
            data, source = self.glb_bin, "the GLB binary chunk"
        elif not isinstance(uri, str):
            raise self.error(f"buffer {i} uri must be a string, got {uri!r}")
        elif uri.startswith("data:"):
            header, comma, payload = uri.partition(",")
            if not comma:
                raise self.error(f"buffer {i} has a malformed data: URI (no comma)")
            try:
                if header.endswith(";base64"):
                    data = base64.b64decode(payload, validate=True)
                else:
                    data = urllib.parse.unquote_to_bytes(payload)
            except (binascii.Error, ValueError) as exc:
                raise self.error(f"buffer {i} has a corrupt base64 data: URI ({exc})") from None
            source = "its data: URI"
        else:
            file = self.external_file(uri, f"buffer {i}")
            try:
                data = file.read_bytes()
            except FileNotFoundError:
                raise self.error(f"buffer {i} refers to the file {uri!r}, which is missing "
                                 f"(looked for {file}); copy it next to the model") from None
            except OSError as exc:
                raise self.error(f"cannot read buffer {i} from {file}: {exc}") from None
            source = f"file {uri!r}"
        if len(data) < declared:
            raise self.error(f"buffer {i} ({source}) holds {len(data)} bytes but declares byteLength "
                             f"{declared}: the file is truncated or the byteLength is wrong")
        data = bytes(data[:declared])
        self._buffers[i] = data
        return data

    def buffer_view(self, i: int, what: str):
        """(bytes of the view's buffer, view start, view end, byteStride or None)."""
        view = self.get("bufferViews", i, f"{what} bufferView")
        buf_index = self.index(view.buffer, "buffers", f"bufferView {i} buffer")
        data = self.buffer(buf_index)
        offset = self.count(view.byteOffset or 0, f"bufferView {i} byteOffset")
        length = self.count(view.byteLength, f"bufferView {i} byteLength", minimum=1)
        if offset + length > len(data):
            raise self.error(f"bufferView {i} spans bytes [{offset}, {offset + length}) but buffer "
                             f"{buf_index} has only {len(data)} bytes")
        stride = view.byteStride
        if stride is not None:
            stride = self.count(stride, f"bufferView {i} byteStride", minimum=1)
        return data, offset, offset + length, stride

    # -- accessors (spec 3.6.2) --
    def accessor(self, i, what: str) -> np.ndarray:
        """Decode accessor ``i``.

        returns : (count,) for SCALAR, (count, c) for VECc, (count, r, r) for MATr (row-major,
            converted from the file's column-major order); float64 for float and normalized
            accessors, int64 otherwise. A fresh array the caller may modify.
        """
        index = self.index(i, "accessors", f"{what} accessor")
        if index not in self._accessors:
            self._accessors[index] = self._decode_accessor(index)
        return self._accessors[index].copy()

    def accessor_info(self, i, what: str):
        """(accessor object, componentType, type, count) after type checks, without decoding."""
        index = self.index(i, "accessors", f"{what} accessor")
        acc = self.items("accessors")[index]
        ctype = acc.componentType
        if ctype not in COMPONENT_DTYPES:
            raise self.error(f"accessor {index} ({what}) has unknown componentType {ctype!r}; "
                             f"glTF allows {sorted(COMPONENT_DTYPES)}")
        if acc.type not in TYPE_SHAPES:
            raise self.error(f"accessor {index} ({what}) has unknown type {acc.type!r}; "
                             f"glTF allows {', '.join(TYPE_SHAPES)}")
        count = self.count(acc.count, f"accessor {index} count", minimum=1)
        return acc, ctype, acc.type, count

    def _read_elements(self, index: int, view_index, byte_offset, ctype: int, type_: str,
                       count: int, tight: bool) -> np.ndarray:
        """Raw components (count, columns, rows) in the file's dtype, bounds-checked.

        Matrix columns start on 4-byte boundaries (spec 3.6.2.4): MAT2 of bytes and MAT3 of
        bytes/shorts carry padding between columns.
        """
        dtype = COMPONENT_DTYPES[ctype]
        columns, rows = TYPE_SHAPES[type_]
        column_bytes = rows * dtype.itemsize
        if columns > 1:
            column_bytes = (column_bytes + 3) // 4 * 4
        element_bytes = columns * column_bytes
        data, start, end, stride = self.buffer_view(view_index, f"accessor {index}")
        if tight or stride is None:
            stride = element_bytes
        if stride < element_bytes:
            raise self.error(f"accessor {index}: byteStride {stride} is smaller than its "
                             f"{element_bytes}-byte elements")
        offset = start + self.count(byte_offset or 0, f"accessor {index} byteOffset")
        last = offset + (count - 1) * stride + element_bytes
        if last > end:
            raise self.error(f"accessor {index} reads bytes [{offset}, {last}) past the end of its "
                             f"bufferView {view_index} (bytes [{start}, {end})): count {count} or "
                             f"byteOffset is wrong, or the file is truncated")
        out = np.empty((count, columns, rows), dtype=dtype)
        for c in range(columns):
            # np.ndarray over the raw bytes with explicit strides reads interleaved and unaligned
            # data without copying; astype below copies
            out[:, c, :] = np.ndarray((count, rows), dtype=dtype, buffer=data,
                                      offset=offset + c * column_bytes,
                                      strides=(stride, dtype.itemsize))
        return out

    def _decode_accessor(self, index: int) -> np.ndarray:
        acc, ctype, type_, count = self.accessor_info(index, "")
        columns, rows = TYPE_SHAPES[type_]
        normalized = bool(acc.normalized)
        if normalized and ctype not in NORMALIZED_DIVISORS:
            raise self.error(f"accessor {index} is normalized but its componentType is "
                             f"{COMPONENT_NAMES[ctype]}; only byte and short types can be")
        if acc.bufferView is not None:
            raw = self._read_elements(index, acc.bufferView, acc.byteOffset, ctype, type_, count,
                                      tight=False)
        else:
            # spec 3.6.2.3: no bufferView means zeros (typically the base of a sparse accessor)
            if count * columns * rows > MAX_BUFFERLESS_COMPONENTS:
                raise self.error(f"accessor {index} has no bufferView and an implausible count "
                                 f"{count}: refusing to allocate it")
            raw = np.zeros((count, columns, rows), dtype=COMPONENT_DTYPES[ctype])
        if acc.sparse is not None:
            self._apply_sparse(index, acc.sparse, raw, ctype, type_, count)
        if normalized:
            values = np.maximum(raw.astype(np.float64) / NORMALIZED_DIVISORS[ctype], -1.0)
        elif ctype == 5126:
            values = raw.astype(np.float64)
        else:
            values = raw.astype(np.int64)
        if type_ == "SCALAR":
            return values.reshape(count)
        if columns == 1:
            return values.reshape(count, rows)
        return values.transpose(0, 2, 1).copy()  # (count, col, row) -> row-major matrices

    def _apply_sparse(self, index, sparse, raw, ctype, type_, count) -> None:
        """Overwrite the elements listed by a sparse accessor (spec 3.6.2.3)."""
        n = self.count(sparse.count, f"accessor {index} sparse count", minimum=1)
        if n > count:
            raise self.error(f"accessor {index} has {n} sparse elements but only {count} elements")
        ind, val = sparse.indices, sparse.values
        if ind is None or val is None:
            raise self.error(f"accessor {index}: sparse needs both 'indices' and 'values'")
        if ind.componentType not in INTEGER_INDEX_TYPES:
            raise self.error(f"accessor {index}: sparse indices must be unsigned byte/short/int, "
                             f"got componentType {ind.componentType!r}")
        where = self._read_elements(index, ind.bufferView, ind.byteOffset, ind.componentType,
                                    "SCALAR", n, tight=True).reshape(n).astype(np.int64)
        if (where >= count).any():
            bad = int(where[where >= count][0])
            raise self.error(f"accessor {index}: sparse index {bad} is out of range (count {count})")
        values = self._read_elements(index, val.bufferView, val.byteOffset, ctype, type_, n,
                                     tight=True)
        raw[where] = values
