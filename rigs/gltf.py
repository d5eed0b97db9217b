"""glTF 2.0 loader: a skinned .glb/.gltf file -> ``Rig``.

pygltflib parses the JSON into dataclasses; everything else is decoded here with numpy, following
the glTF 2.0 specification (section 3.6 "Binary data storage", 3.7 "Geometry", 3.8 "Transforms and
skinning", 3.11 "Animations"):

* accessors of every component type, ``normalized`` integers, ``byteStride``, accessor and
  bufferView ``byteOffset``, matrix column padding, sparse accessors, accessors without bufferView;
* buffers from a GLB binary chunk, ``data:`` URIs and external files next to the .gltf;
* all triangle primitives (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) of all skinned mesh nodes of
  the default scene, merged into one mesh; JOINTS_n/WEIGHTS_n sets reduced to 4 influences;
* every skin used, merged into one skeleton (joints plus all their ancestors);
* TRS and matrix node transforms, animations of skeleton nodes.

A file is untrusted input: pygltflib checks neither types nor ranges, so every index, count and
offset is checked here before use, and every problem becomes a ``ModelFormatError`` that names the
file and the offending object (``NoSkinError`` when the file is valid but holds no skin). The
loader never returns NaN or infinity.

Precision: glTF stores positions, weights, inverse bind matrices and keyframes as float32; they are
returned as float64 holding exactly the float32 values, except the weights, which are renormalised
in float64 so that every row sums to 1 (``check_mesh``). Files written by ``save_gltf`` carry the
float64 weights' rounding residuals in two application-specific attributes (``WEIGHT_RESIDUALS``),
from which they are rebuilt exactly; other readers ignore them and use the float32 WEIGHTS_0.
"""
from __future__ import annotations

import base64
import binascii
import heapq
import json
import os
import struct
import sys
import urllib.parse
import warnings
from pathlib import Path

import numpy as np
import pygltflib

from ..algebra.transforms import matrix_to_quat, matrix_to_trs, quat_to_matrix, trs_matrix
from ..errors import CgaskinError, InvalidInputError, ModelFormatError, NoSkinError
from ..animation.rig import CHANNEL_PATHS, INTERPOLATIONS, Channel, Clip, Rig, Skeleton
from ..animation import validate
from ..animation.validate import check_mesh

__all__ = ["load_gltf", "trs_to_matrix", "matrix_to_trs", "quat_to_matrix", "matrix_to_quat"]

# --- glTF constants (spec 3.6.2) ---------------------------------------------------------------
COMPONENT_DTYPES = {
    5120: np.dtype("<i1"),  # BYTE
    5121: np.dtype("<u1"),  # UNSIGNED_BYTE
    5122: np.dtype("<i2"),  # SHORT
    5123: np.dtype("<u2"),  # UNSIGNED_SHORT
    5125: np.dtype("<u4"),  # UNSIGNED_INT
    5126: np.dtype("<f4"),  # FLOAT
}
COMPONENT_NAMES = {5120: "byte", 5121: "unsigned byte", 5122: "short", 5123: "unsigned short",
                   5125: "unsigned int", 5126: "float"}
#: (columns, rows) of each accessor type; vectors are a single column
TYPE_SHAPES = {"SCALAR": (1, 1), "VEC2": (1, 2), "VEC3": (1, 3), "VEC4": (1, 4),
               "MAT2": (2, 2), "MAT3": (3, 3), "MAT4": (4, 4)}
#: spec 3.11 "normalized" integers: f = max(c / (2^(bits-1) - 1), -1) signed, c / (2^bits - 1) unsigned
NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
INTEGER_INDEX_TYPES = (5121, 5123, 5125)

GLB_MAGIC = b"glTF"
GLB_JSON_CHUNK = 0x4E4F534A
GLB_BIN_CHUNK = 0x004E4942

MODE_NAMES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP", 4: "TRIANGLES",
              5: "TRIANGLE_STRIP", 6: "TRIANGLE_FAN"}
#: extensions that change how geometry is stored: files that require them cannot be read here
UNSUPPORTED_EXTENSIONS = {"KHR_draco_mesh_compression", "EXT_meshopt_compression",
                          "KHR_meshopt_compression"}
#: an accessor without bufferView is materialised as zeros: refuse absurd counts (a corrupted
#: file must not make us allocate gigabytes)
MAX_BUFFERLESS_COMPONENTS = 1 << 26
#: quaternions further than this from unit length are renormalised; closer ones are kept as
#: stored so that a save -> load round trip is exact (renormalising is not idempotent in floats)
QUAT_UNIT_TOLERANCE = 1e-12
#: application-specific attributes (spec 3.7.2.1: custom semantics start with "_") that cgaskin
#: writes next to WEIGHTS_n: float64 weights w = (WEIGHTS_n + LO) + LO2 exactly, all float32
WEIGHT_RESIDUALS = ("_CGASKIN_WEIGHTS_{}_LO", "_CGASKIN_WEIGHTS_{}_LO2")
#: inverse bind matrices and node matrices must be affine: last row (0, 0, 0, 1) within this
AFFINE_TOLERANCE = 1e-6


#: directories of cgaskin's modules: warnings point past them, at the user's call
_PACKAGE_DIRS = {os.path.dirname(__file__), os.path.dirname(validate.__file__)}


# --- transforms (shared with the exporter) -----------------------------------------------------

def trs_to_matrix(translation, rotation, scale) -> np.ndarray:
    """The glTF local matrix T @ R @ S (see ``cgaskin.algebra.transforms.trs_matrix``).

    translation : (3,) float; rotation : (4,) float unit quaternion (x, y, z, w); scale : (3,) float
    returns : (4, 4) float64
    """
    return trs_matrix(translation, rotation, scale)


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
        level, frame = 1, sys._getframe(0)
        while frame is not None and os.path.dirname(frame.f_code.co_filename) in _PACKAGE_DIRS:
            frame, level = frame.f_back, level + 1
        warnings.warn(f"{self.path.name}: {message}" if prefix else message, UserWarning, stacklevel=level)

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
            if "://" in uri:
                raise self.error(f"buffer {i} refers to {uri!r}: only files next to the model and "
                                 f"data: URIs are supported (download it first)")
            file = self.path.parent / urllib.parse.unquote(uri)
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


# --- reading the container --------------------------------------------------------------------

def _read_document(path: Path) -> _GltfFile:
    """Read a .gltf or .glb file (told apart by content, not by extension)."""
    name = path.name
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise ModelFormatError(f"{name}: no such file ({path})") from None
    except IsADirectoryError:
        raise ModelFormatError(f"{name}: is a directory, not a glTF file ({path})") from None
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


# --- scene graph --------------------------------------------------------------------------------

def _parents(f: _GltfFile) -> list[int]:
    """Parent of every node (-1 for roots); refuses nodes with two parents and cycles."""
    nodes = f.items("nodes")
    parents = [-1] * len(nodes)
    for i, node in enumerate(nodes):
        children = node.children or []
        if not isinstance(children, list):
            raise f.error(f"node {i} children must be a list, got {children!r}")
        for c in children:
            c = f.index(c, "nodes", f"node {i} child")
            if parents[c] != -1 or c == i:
                raise f.error(f"node {c} is a child of both node {parents[c] if c != i else i} and "
                              f"node {i}: the node hierarchy must be a tree")
            parents[c] = i
    # with at most one parent each, a node unreachable from the roots lies on a cycle
    reachable = [p == -1 for p in parents]
    stack = [i for i, p in enumerate(parents) if p == -1]
    while stack:
        i = stack.pop()
        for c in nodes[i].children or []:
            if not reachable[c]:
                reachable[c] = True
                stack.append(c)
    if not all(reachable):
        raise f.error(f"the node hierarchy has a cycle through node {reachable.index(False)}")
    return parents


def _scene_nodes(f: _GltfFile, parents: list[int]) -> list[int]:
    """Nodes of the default scene in depth-first pre-order (all nodes if there is no scene)."""
    nodes = f.items("nodes")
    if not nodes:
        raise f.error("the file holds no node at all, so no mesh and no skin")
    scenes = f.items("scenes")
    if f.doc.scene is not None:
        scene = f.get("scenes", f.doc.scene, "the default 'scene'")
    else:
        # no default scene: the first one is what viewers show; without any, take every root
        scene = scenes[0] if scenes else None
    if scene is None:
        roots = [i for i, p in enumerate(parents) if p == -1]
    else:
        roots = [f.index(r, "nodes", "scene node") for r in (scene.nodes or [])]
    order, seen = [], set()
    stack = list(reversed(roots))
    while stack:
        i = stack.pop()
        if i in seen:
            continue
        seen.add(i)
        order.append(i)
        stack.extend(reversed(nodes[i].children or []))
    return order


def _node_transform(f: _GltfFile, i: int, node):
    """(translation (3,), rotation (4,), scale (3,), matrix (4, 4)) of a node, float64."""
    trs_given = any(v is not None for v in (node.translation, node.rotation, node.scale))
    if node.matrix is not None:
        # the file stores matrices column-major (spec 3.5.3)
        m = f.floats(node.matrix, 16, f"node {i} matrix").reshape(4, 4).T.copy()
        if not (trs_given and np.array_equal(m, np.eye(4))):
            if trs_given:
                f.warn(f"node {i} has both a matrix and TRS; used the matrix")
            if np.abs(m[3] - [0, 0, 0, 1]).max() > AFFINE_TOLERANCE:
                raise f.error(f"node {i} matrix is not affine (last row {m[3].tolist()})")
            t, q, s = matrix_to_trs(m)
            return t, q, s, m
    t = f.floats(node.translation, 3, f"node {i} translation") if node.translation is not None else np.zeros(3)
    q = f.floats(node.rotation, 4, f"node {i} rotation") if node.rotation is not None else np.array([0.0, 0, 0, 1])
    s = f.floats(node.scale, 3, f"node {i} scale") if node.scale is not None else np.ones(3)
    norm = np.linalg.norm(q)
    if norm == 0:
        raise f.error(f"node {i} rotation is the zero quaternion")
    if abs(norm - 1.0) > QUAT_UNIT_TOLERANCE:
        q = q / norm
    m = trs_to_matrix(t, q, s)
    if not np.isfinite(m).all():
        raise f.error(f"node {i} transform overflows (translation {t}, scale {s})")
    return t, q, s, m


# --- meshes -----------------------------------------------------------------------------------------

def _attribute_map(f: _GltfFile, prim, where: str) -> dict:
    attrs = prim.attributes
    if isinstance(attrs, pygltflib.Attributes):
        attrs = vars(attrs)
    if not isinstance(attrs, dict):
        raise f.error(f"{where}: attributes must be a JSON object, got {attrs!r}")
    return {k: v for k, v in attrs.items() if v is not None}


def _triangles(f: _GltfFile, mode: int, idx: np.ndarray, where: str) -> np.ndarray:
    """Faces (m, 3) int64 of a TRIANGLES / TRIANGLE_STRIP / TRIANGLE_FAN index sequence."""
    n = len(idx)
    if mode == 4:
        if n % 3:
            raise f.error(f"{where}: TRIANGLES needs a multiple of 3 indices/vertices, got {n}")
        return idx.reshape(-1, 3)
    if n < 3:
        return np.zeros((0, 3), dtype=np.int64)
    i = np.arange(n - 2)
    if mode == 5:
        # spec 3.7.2.1: triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), which keeps the winding
        faces = np.stack([idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]], axis=1)
    else:
        faces = np.stack([idx[i + 1], idx[i + 2], np.full(n - 2, idx[0])], axis=1)
    # strips are stitched with degenerate triangles: they carry no surface, drop them
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return faces[keep]


def _read_primitive(f: _GltfFile, m: int, p: int, prim, skinned: bool):
    """Decode one triangle primitive; for points and lines return the mode's name instead.

    returns dict: positions (n, 3) float64, faces (m, 3) int64, joints (n, 4s) int64,
        weights (n, 4s) float64, attributes {name: (n, c) float64}
    """
    where = f"mesh {m} primitive {p}"
    mode = 4 if prim.mode is None else prim.mode
    if mode not in MODE_NAMES:
        raise f.error(f"{where} has unknown mode {mode!r}")
    if mode < 4:
        return MODE_NAMES[mode]
    attrs = _attribute_map(f, prim, where)
    if "POSITION" not in attrs:
        raise f.error(f"{where} has no POSITION attribute")
    _, _, ptype, n = f.accessor_info(attrs["POSITION"], f"{where} POSITION")
    if ptype != "VEC3":
        raise f.error(f"{where} POSITION must be VEC3, got {ptype}")
    for name, acc in attrs.items():
        count = f.accessor_info(acc, f"{where} {name}")[3]
        if count != n:
            raise f.error(f"{where}: attribute {name} has {count} elements but POSITION has {n}; "
                          f"all attributes of a primitive must have one element per vertex")
    positions = f.accessor(attrs["POSITION"], f"{where} POSITION").astype(np.float64)
    bad = ~np.isfinite(positions)
    if bad.any():
        v = int(np.flatnonzero(bad.any(axis=1))[0])
        raise f.error(f"{where} POSITION (accessor {attrs['POSITION']}) holds non-finite coordinates: "
                      f"vertex {v} is {positions[v].tolist()} ({int(bad.any(axis=1).sum())} such vertices)")

    if prim.indices is not None:
        _, ctype, itype, _ = f.accessor_info(prim.indices, f"{where} indices")
        if ctype not in INTEGER_INDEX_TYPES or itype != "SCALAR":
            raise f.error(f"{where} indices must be SCALAR unsigned byte/short/int, got "
                          f"{itype} {COMPONENT_NAMES[ctype]}")
        idx = f.accessor(prim.indices, f"{where} indices")
        bad = idx >= n
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise f.error(f"{where}: index {int(idx[k])} at position {k} of accessor {prim.indices} "
                          f"is out of range: the primitive has {n} vertices "
                          f"({int(bad.sum())} bad indices)")
    else:
        idx = np.arange(n, dtype=np.int64)  # non-indexed: vertices taken in order
    faces = _triangles(f, mode, idx, where)

    out = {"positions": positions, "faces": faces, "attributes": {}}
    residuals = {r.format(s) for r in WEIGHT_RESIDUALS for s in range(8)}
    # NORMAL, TEXCOORD_0 and application-specific attributes ("_NAME", e.g. the tear's "_TEAR"
    # labels): carried through cut, tear and export
    custom = [(name, None) for name in attrs if name.startswith("_") and name not in residuals]
    for name, width in (("NORMAL", 3), ("TEXCOORD_0", 2), *custom):
        if name in attrs:
            _, ctype, atype, _ = f.accessor_info(attrs[name], f"{where} {name}")
            values = f.accessor(attrs[name], f"{where} {name}")
            if values.ndim == 1:
                values = values[:, None]
            if values.ndim != 2 or (width is not None and values.shape[1] != width) or values.dtype != np.float64:
                raise f.error(f"{where} {name} must be VEC{width or 'n'} of floats or normalized "
                              f"integers, got {atype} {COMPONENT_NAMES[ctype]}")
            if not np.isfinite(values).all():
                v = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])
                raise f.error(f"{where} {name} holds non-finite values (vertex {v}: {values[v].tolist()})")
            out["attributes"][name] = values

    sets = sorted({int(k.split("_")[1]) for k in attrs
                   if k.split("_")[0] in ("JOINTS", "WEIGHTS") and k.split("_")[-1].isdigit()})
    for s in sets:
        if f"JOINTS_{s}" not in attrs or f"WEIGHTS_{s}" not in attrs:
            raise f.error(f"{where} has only one of JOINTS_{s} / WEIGHTS_{s}; they come in pairs")
    if skinned and 0 not in sets:
        raise f.error(f"{where} belongs to a skinned node but has no JOINTS_0/WEIGHTS_0")
    joints, weights = [], []
    for s in sets:
        _, jtype, jshape, _ = f.accessor_info(attrs[f"JOINTS_{s}"], f"{where} JOINTS_{s}")
        _, wtype, wshape, _ = f.accessor_info(attrs[f"WEIGHTS_{s}"], f"{where} WEIGHTS_{s}")
        j = f.accessor(attrs[f"JOINTS_{s}"], f"{where} JOINTS_{s}")
        w = f.accessor(attrs[f"WEIGHTS_{s}"], f"{where} WEIGHTS_{s}")
        if jshape != "VEC4" or j.dtype != np.int64:
            raise f.error(f"{where} JOINTS_{s} must be VEC4 unsigned byte/short, got "
                          f"{jshape} {COMPONENT_NAMES[jtype]}{' normalized' if j.dtype != np.int64 else ''}")
        if wshape != "VEC4" or w.dtype != np.float64:
            raise f.error(f"{where} WEIGHTS_{s} must be VEC4 float or normalized unsigned "
                          f"byte/short, got {wshape} {COMPONENT_NAMES[wtype]} (not normalized)")
        for name in (r.format(s) for r in WEIGHT_RESIDUALS):
            if name in attrs:  # written by save_gltf: restores the float64 weights exactly
                residual = f.accessor(attrs[name], f"{where} {name}")
                if residual.shape != w.shape or residual.dtype != np.float64:
                    raise f.error(f"{where} {name} must be VEC4 float like WEIGHTS_{s}")
                w = w + residual
        joints.append(j)
        weights.append(w)
    out["joints"] = np.concatenate(joints, axis=1) if joints else np.zeros((n, 0), dtype=np.int64)
    out["weights"] = np.concatenate(weights, axis=1) if weights else np.zeros((n, 0))
    return out


# --- skins and skeleton -------------------------------------------------------------------------

def _read_skins(f: _GltfFile, skin_indices: list[int]):
    """Merge the bones of the given skins.

    Returns bone_nodes (file node index per bone), inverse_bind (b, 4, 4), and for each skin the
    map from its joint slot to the global bone index. A bone is a (node, inverse bind matrix)
    pair: skins that share a joint with the same matrix share the bone.
    """
    bone_nodes, inverse_bind, keys, maps = [], [], {}, {}
    for s in skin_indices:
        skin = f.items("skins")[s]
        joints = skin.joints or []
        if not isinstance(joints, list) or not joints:
            raise f.error(f"skin {s} has no joints")
        joints = [f.index(j, "nodes", f"skin {s} joint") for j in joints]
        if skin.inverseBindMatrices is None:
            ibm = np.broadcast_to(np.eye(4), (len(joints), 4, 4))  # spec: identity by default
        else:
            acc, ctype, atype, count = f.accessor_info(skin.inverseBindMatrices,
                                                       f"skin {s} inverseBindMatrices")
            if atype != "MAT4" or ctype != 5126:
                raise f.error(f"skin {s} inverseBindMatrices must be MAT4 float, got {atype} "
                              f"{COMPONENT_NAMES[ctype]}")
            if count < len(joints):
                raise f.error(f"skin {s} has {len(joints)} joints but only {count} inverse bind matrices")
            ibm = f.accessor(skin.inverseBindMatrices, f"skin {s} inverseBindMatrices")[:len(joints)]
            if not np.isfinite(ibm).all():
                k = int(np.flatnonzero(~np.isfinite(ibm).all(axis=(1, 2)))[0])
                raise f.error(f"skin {s}: inverse bind matrix {k} holds non-finite values")
            bad = np.abs(ibm[:, 3] - [0, 0, 0, 1]).max(axis=1) > AFFINE_TOLERANCE
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise f.error(f"skin {s}: inverse bind matrix {k} is not affine (last row "
                              f"{ibm[k, 3].tolist()})")
        slot_map = np.empty(len(joints), dtype=np.int64)
        for k, (node, matrix) in enumerate(zip(joints, ibm)):
            key = (node, np.asarray(matrix, dtype=np.float64).tobytes())
            if key not in keys:
                keys[key] = len(bone_nodes)
                bone_nodes.append(node)
                inverse_bind.append(np.array(matrix, dtype=np.float64))
            slot_map[k] = keys[key]
        maps[s] = slot_map
    return bone_nodes, np.array(inverse_bind).reshape(-1, 4, 4), maps


def _skeleton_order(bone_nodes: list[int], parents: list[int], children) -> list[int]:
    """Joints and all their ancestors, parents first, otherwise in file order.

    A heap always releases the smallest available node index: files whose parents precede their
    children (and everything ``save_gltf`` writes) keep their node order exactly.
    """
    members = set()
    for node in bone_nodes:
        while node != -1 and node not in members:
            members.add(node)
            node = parents[node]
    heap = [i for i in members if parents[i] == -1]
    heapq.heapify(heap)
    order = []
    while heap:
        i = heapq.heappop(heap)
        order.append(i)
        for c in children(i):
            if c in members:
                heapq.heappush(heap, c)
    return order


def _unique_names(f: _GltfFile, order: list[int]) -> list[str]:
    names, used = [], set()
    for i in order:
        name = f.items("nodes")[i].name
        name = name if isinstance(name, str) and name else f"node{i}"
        if name in used:  # names must be unique to address joints by name
            base, k = name, 1
            while f"{base}.{k}" in used:
                k += 1
            name = f"{base}.{k}"
        used.add(name)
        names.append(name)
    return names


# --- animations -----------------------------------------------------------------------------------

def _read_clips(f: _GltfFile, node_to_skeleton: dict) -> list[Clip]:
    clips = []
    skipped = {"weights": 0, "other": 0}
    for a, anim in enumerate(f.items("animations")):
        name = anim.name if isinstance(anim.name, str) and anim.name else f"clip{a}"
        samplers = anim.samplers or []
        channels = []
        for c, ch in enumerate(anim.channels or []):
            where = f"animation {a} ({name!r}) channel {c}"
            target = ch.target
            path = getattr(target, "path", None)
            node = getattr(target, "node", None)
            if path == "weights":
                skipped["weights"] += 1
                continue
            if path not in CHANNEL_PATHS or node not in node_to_skeleton:
                if node is not None:
                    f.index(node, "nodes", f"{where} target node")
                skipped["other"] += 1
                continue
            if isinstance(ch.sampler, bool) or not isinstance(ch.sampler, int) or not 0 <= ch.sampler < len(samplers):
                raise f.error(f"{where} sampler {ch.sampler!r} is out of range ({len(samplers)} samplers)")
            sampler = samplers[ch.sampler]
            interpolation = sampler.interpolation or "LINEAR"
            if interpolation not in INTERPOLATIONS:
                raise f.error(f"{where}: unknown interpolation {interpolation!r}; glTF allows "
                              f"{', '.join(INTERPOLATIONS)}")
            _, ttype, tshape, k = f.accessor_info(sampler.input, f"{where} input")
            if ttype != 5126 or tshape != "SCALAR":
                raise f.error(f"{where}: key times must be SCALAR float, got {tshape} {COMPONENT_NAMES[ttype]}")
            times = f.accessor(sampler.input, f"{where} input")
            if not np.isfinite(times).all():
                raise f.error(f"{where}: key times hold non-finite values")
            steps = np.diff(times)
            if (steps <= 0).any():
                i = int(np.flatnonzero(steps <= 0)[0])
                raise f.error(f"{where}: key times must increase strictly, but key {i + 1} "
                              f"(t={times[i + 1]}) follows t={times[i]}")
            width = CHANNEL_PATHS[path]
            _, vtype, vshape, vcount = f.accessor_info(sampler.output, f"{where} output")
            if vshape != f"VEC{width}":
                raise f.error(f"{where}: {path} values must be VEC{width}, got {vshape}")
            per_key = 3 if interpolation == "CUBICSPLINE" else 1
            if vcount != per_key * k:
                raise f.error(f"{where}: {k} key times need {per_key * k} {interpolation} output "
                              f"values, the output accessor has {vcount}")
            values = f.accessor(sampler.output, f"{where} output")
            if values.dtype != np.float64:
                raise f.error(f"{where}: {path} values must be float or normalized integers, got "
                              f"{COMPONENT_NAMES[vtype]}")
            if not np.isfinite(values).all():
                raise f.error(f"{where}: keyframe values hold non-finite numbers")
            if per_key == 3:
                values = values.reshape(k, 3, width)  # (in-tangent, value, out-tangent) per key
            channels.append(Channel(node=node_to_skeleton[node], path=path, interpolation=interpolation,
                                    times=times, values=values))
        clips.append(Clip(name=name, channels=tuple(channels)))
    if skipped["weights"] or skipped["other"]:
        f.warn(f"skipped {skipped['weights']} animation channels of morph-target weights and "
               f"{skipped['other']} of nodes outside the skeleton (cgaskin animates skeleton nodes only)")
    return clips


# --- the loader ---------------------------------------------------------------------------------------

def load_gltf(path) -> Rig:
    """Load a skinned glTF 2.0 file (.glb or .gltf) as a ``Rig``.

    Every node with both ``mesh`` and ``skin`` in the default scene (all nodes when the file has no
    scene) contributes all its triangle primitives, merged in scene order into one mesh; the
    mesh nodes' own transforms are ignored (glTF skinning semantics). The skeleton holds the joints
    of every skin used and all their ancestors. Influences beyond 4 are reduced to the largest 4
    and weight rows renormalised (with a warning, see ``check_mesh``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Rig
        vertices (n, 3) float64, faces (m, 3) int64, joints (n, 4) int64, weights (n, 4) float64
        (rows sum to 1 in float64), skeleton, clips (one per animation, named ``animation.name`` or
        ``clip{i}``), attributes NORMAL (n, 3) / TEXCOORD_0 (n, 2) when every primitive has them,
        name = the file's stem.

    Raises
    ------
    ModelFormatError
        The file is missing, truncated, not glTF 2.0, or inconsistent (the message says where).
    NoSkinError
        The file is valid but holds no skinned mesh.
    """
    path = Path(path)
    f = _read_document(path)
    try:
        return _build_rig(f)
    except CgaskinError:
        raise
    except (TypeError, AttributeError, KeyError, IndexError, ValueError, OverflowError,
            MemoryError) as exc:
        # Safety net: every check above is explicit, but a corrupted document can put any JSON
        # value anywhere; whatever slipped through is still the file's fault, not a crash.
        raise ModelFormatError(f"{path.name}: malformed glTF ({type(exc).__name__}: {exc})") from exc


def _build_rig(f: _GltfFile) -> Rig:
    nodes = f.items("nodes")
    parents = _parents(f)
    scene_nodes = _scene_nodes(f, parents)

    skinned, rigid = [], []
    for i in scene_nodes:
        node = nodes[i]
        if node.mesh is None:
            continue
        f.index(node.mesh, "meshes", f"node {i} mesh")
        if node.skin is None:
            rigid.append(i)
        else:
            skinned.append((i, f.index(node.skin, "skins", f"node {i} skin")))
    if not skinned:
        # Decode the rigid meshes anyway, so that a broken file gets its specific error rather
        # than a generic "no skin".
        for i in rigid:
            mesh = f.items("meshes")[nodes[i].mesh]
            for p, prim in enumerate(mesh.primitives or []):
                _read_primitive(f, nodes[i].mesh, p, prim, skinned=False)
        what = (f"{len(rigid)} mesh node(s) without a skin" if rigid else "no mesh in its scene")
        raise f.error(f"holds no skinned mesh ({what}); cgaskin needs a skin "
                      f"(JOINTS_0/WEIGHTS_0 + node.skin)", cls=NoSkinError)

    skin_indices = sorted({s for _, s in skinned})
    bone_file_nodes, inverse_bind, slot_maps = _read_skins(f, skin_indices)
    n_bones = len(bone_file_nodes)

    # --- merge the primitives -------------------------------------------------------------------
    parts, skipped_modes = [], []
    for i, s in skinned:
        m = nodes[i].mesh
        primitives = f.items("meshes")[m].primitives or []
        for p, prim in enumerate(primitives):
            part = _read_primitive(f, m, p, prim, skinned=True)
            if isinstance(part, str):
                skipped_modes.append(part)
                continue
            j, w = part["joints"], part["weights"]
            slots = slot_maps[s]
            bad = (w > 0) & ((j < 0) | (j >= len(slots)))
            if bad.any():
                v = int(np.flatnonzero(bad.any(axis=1))[0])
                raise f.error(f"mesh {m} primitive {p}: vertex {v} is weighted to joint "
                              f"{int(j[bad][0])} but skin {s} has {len(slots)} joints")
            j = np.where(w > 0, j, 0)  # unused slots may hold anything: point them at slot 0
            part["joints"] = slots[j]
            parts.append(part)
    if skipped_modes:
        f.warn(f"skipped {len(skipped_modes)} primitives that are not triangles "
               f"({', '.join(sorted(set(skipped_modes)))})")
    if not parts:
        raise f.error("the skinned meshes hold no triangle primitive", cls=NoSkinError)

    offsets = np.cumsum([0] + [len(part["positions"]) for part in parts])
    vertices = np.concatenate([part["positions"] for part in parts])
    faces = np.concatenate([part["faces"] + off for part, off in zip(parts, offsets)])
    width = max(part["weights"].shape[1] for part in parts)

    def padded(key, dtype):
        return np.concatenate([np.pad(part[key], ((0, 0), (0, width - part[key].shape[1])))
                               for part in parts]).astype(dtype)

    joints, weights = padded("joints", np.int64), padded("weights", np.float64)
    attributes = {}
    names = dict.fromkeys(name for part in parts for name in part["attributes"])
    for name in names:
        have = [name in part["attributes"] for part in parts]
        if all(have):
            attributes[name] = np.concatenate([part["attributes"][name] for part in parts])
        elif any(have):
            f.warn(f"dropped attribute {name}: only {sum(have)} of {len(parts)} merged primitives have it")
    if len(faces) == 0:
        raise f.error("the skinned meshes hold no triangle (all primitives are empty or degenerate)")

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            vertices, faces, joints, weights = check_mesh(vertices, faces, joints, weights,
                                                          n_bones=n_bones, source=f.path.name)
    except InvalidInputError as exc:
        raise ModelFormatError(str(exc)) from None
    for warning in caught:  # re-issued so that they point at the caller of load, not in here
        f.warn(str(warning.message), prefix=False)

    # --- skeleton -----------------------------------------------------------------------------------
    order = _skeleton_order(bone_file_nodes, parents, lambda i: nodes[i].children or [])
    node_to_skeleton = {node: k for k, node in enumerate(order)}
    transforms = [_node_transform(f, i, nodes[i]) for i in order]
    skeleton = Skeleton(
        names=_unique_names(f, order),
        parents=np.array([node_to_skeleton[parents[i]] if parents[i] != -1 else -1 for i in order],
                         dtype=np.int64),
        rest_translations=np.array([t[0] for t in transforms]).reshape(-1, 3),
        rest_rotations=np.array([t[1] for t in transforms]).reshape(-1, 4),
        rest_scales=np.array([t[2] for t in transforms]).reshape(-1, 3),
        rest_matrices=np.array([t[3] for t in transforms]).reshape(-1, 4, 4),
        bone_nodes=np.array([node_to_skeleton[i] for i in bone_file_nodes], dtype=np.int64),
        inverse_bind=inverse_bind,
    )
    clips = _read_clips(f, node_to_skeleton)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights, skeleton=skeleton,
               clips=clips, attributes=attributes, name=f.path.stem)
