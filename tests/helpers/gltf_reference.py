"""An independent glTF 2.0 skinning oracle, written from the glTF 2.0 specification.

It reads files with pygltflib and numpy only: no code of ``cgaskin`` (neither its loader nor its
math), so that the tests can compare ``cgaskin.skin`` against a second, separately written reading of
the specification. Simplicity beats speed here.

What the specification says, and this module does (section numbers of glTF 2.0):

* accessors (3.6): component types, ``normalized`` integer decoding, ``byteStride``, matrix column
  padding, sparse substitution; buffers from the GLB BIN chunk, ``data:`` URIs or files next to the
  ``.gltf``;
* node transforms (3.5.3): ``matrix`` (column-major) or ``T * R * S``; globals along the node tree;
* animation samplers (3.11 and Appendix C): STEP, LINEAR (quaternions by slerp along the shorter
  arc), CUBICSPLINE (tangents scaled by the key interval, rotations normalised afterwards); times
  outside the keys clamp to the first/last value;
* skinning (3.7.3): joint matrix = global(joint) * inverseBindMatrix; the skinned mesh node's own
  transform is ignored; every ``JOINTS_n``/``WEIGHTS_n`` set is applied.

Morph targets and KHR extensions are out of scope.
"""
from __future__ import annotations

import base64
import pathlib
import urllib.parse

import numpy as np
import pygltflib

_COMPONENT_DTYPES = {
    5120: np.dtype("<i1"), 5121: np.dtype("<u1"), 5122: np.dtype("<i2"),
    5123: np.dtype("<u2"), 5125: np.dtype("<u4"), 5126: np.dtype("<f4"),
}
# type -> (rows, columns); vectors are a single column
_TYPE_SHAPES = {
    "SCALAR": (1, 1), "VEC2": (2, 1), "VEC3": (3, 1), "VEC4": (4, 1),
    "MAT2": (2, 2), "MAT3": (3, 3), "MAT4": (4, 4),
}
_TRIANGLES = 4


class _File:
    """A glTF document with its buffers loaded as bytes."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self.gltf = pygltflib.GLTF2().load(str(self.path))
        self._buffers = {}

    def buffer(self, index) -> bytes:
        if index not in self._buffers:
            buf = self.gltf.buffers[index]
            if buf.uri is None:
                # GLB: the buffer without a URI is the BIN chunk.
                data = self.gltf.binary_blob()
            elif buf.uri.startswith("data:"):
                data = base64.b64decode(buf.uri.split(",", 1)[1])
            else:
                data = (self.path.parent / urllib.parse.unquote(buf.uri)).read_bytes()
            self._buffers[index] = bytes(data)
        return self._buffers[index]

    def _read_view(self, view_index, byte_offset, count, dtype, rows, cols):
        """Elements of a buffer view as a (count, rows * cols) array in column-major element order."""
        view = self.gltf.bufferViews[view_index]
        data = self.buffer(view.buffer)
        start = (view.byteOffset or 0) + (byte_offset or 0)
        # Spec 3.6.2.4: each matrix column starts on a 4-byte boundary.
        column_bytes = -(-rows * dtype.itemsize // 4) * 4 if cols > 1 else rows * dtype.itemsize
        element_bytes = column_bytes * cols
        stride = view.byteStride or element_bytes
        out = np.empty((count, rows * cols), dtype=dtype)
        for c in range(cols):
            column = np.ndarray(shape=(count, rows), dtype=dtype, buffer=data,
                                offset=start + c * column_bytes, strides=(stride, dtype.itemsize))
            out[:, c * rows:(c + 1) * rows] = column
        return out

    def accessor(self, index) -> np.ndarray:
        """Decoded accessor: (count,) for SCALAR, (count, k) for vectors, (count, r, c) for matrices
        (indexed ``[row, column]``). Normalised integers become float64 per the spec's formulas;
        other integers stay integers, floats become float64."""
        acc = self.gltf.accessors[index]
        dtype = _COMPONENT_DTYPES[acc.componentType]
        rows, cols = _TYPE_SHAPES[acc.type]
        if acc.bufferView is not None:
            raw = self._read_view(acc.bufferView, acc.byteOffset, acc.count, dtype, rows, cols)
        else:
            raw = np.zeros((acc.count, rows * cols), dtype=dtype)
        if acc.sparse is not None and acc.sparse.count:
            sp = acc.sparse
            idx = self._read_view(sp.indices.bufferView, sp.indices.byteOffset, sp.count,
                                  _COMPONENT_DTYPES[sp.indices.componentType], 1, 1)[:, 0]
            vals = self._read_view(sp.values.bufferView, sp.values.byteOffset, sp.count, dtype, rows, cols)
            raw = raw.copy()
            raw[idx.astype(np.int64)] = vals
        if dtype.kind == "f":
            out = raw.astype(np.float64)
        elif acc.normalized:
            # Spec 3.11: unsigned c / (2^n - 1); signed max(c / (2^(n-1) - 1), -1).
            info = np.iinfo(dtype)
            out = np.maximum(raw.astype(np.float64) / info.max, -1.0)
        else:
            out = raw.astype(np.int64)
        if acc.type == "SCALAR":
            return out[:, 0]
        if cols > 1:
            # Stored column-major: element (count, col, row) -> transpose to [row, column].
            return out.reshape(acc.count, cols, rows).transpose(0, 2, 1)
        return out


# --------------------------------------------------------------------------------------------------
# Transforms


def _quat_matrix(q):
    x, y, z, w = np.asarray(q, dtype=np.float64) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _trs(t, r, s):
    m = np.eye(4)
    m[:3, :3] = _quat_matrix(r) @ np.diag(s)
    m[:3, 3] = t
    return m


def _slerp(a, b, u):
    # Keys are rotations, so they are taken as unit quaternions: the spec requires unit rotation
    # outputs, and files that store them off unit (float32 rounding ~1e-8; simple_skin.gltf stores
    # (0, 0, -0.707, 0.707), off by 1.5e-4) would otherwise shift the slerp parameter by the
    # difference of the two norms. cgaskin makes the same choice.
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    d = float(np.dot(a, b))
    if d < 0:            # take the shorter arc
        b, d = -b, -d
    if d > 1 - 1e-12:    # (nearly) equal: the limit of slerp is lerp
        q = (1 - u) * a + u * b
    else:
        theta = np.arccos(min(d, 1.0))
        q = (np.sin((1 - u) * theta) * a + np.sin(u * theta) * b) / np.sin(theta)
    return q / np.linalg.norm(q)


def sample(times, values, interpolation, path, t):
    """Value of one animation sampler at time ``t`` (spec 3.11 and Appendix C).

    times : (k,) float64 key times
    values : (k, c) float64, or (3k, c) for CUBICSPLINE (in-tangent, value, out-tangent per key)
    returns (c,) float64
    """
    times = np.asarray(times, dtype=np.float64)
    values = np.asarray(values, dtype=np.float64)
    cubic = interpolation == "CUBICSPLINE"
    keys = values.reshape(len(times), 3, -1)[:, 1] if cubic else values
    rotation = path == "rotation"
    if t <= times[0] or len(times) == 1:
        out = keys[0]
    elif t >= times[-1]:
        out = keys[-1]
    else:
        k = int(np.searchsorted(times, t, side="right")) - 1
        dt = times[k + 1] - times[k]
        u = (t - times[k]) / dt
        if interpolation == "STEP":
            out = keys[k]
        elif interpolation == "LINEAR":
            out = _slerp(keys[k], keys[k + 1], u) if rotation else (1 - u) * keys[k] + u * keys[k + 1]
        elif cubic:
            v = values.reshape(len(times), 3, -1)
            p0, m0 = v[k, 1], dt * v[k, 2]            # value and out-tangent of key k
            p1, m1 = v[k + 1, 1], dt * v[k + 1, 0]    # value and in-tangent of key k + 1
            u2, u3 = u * u, u * u * u
            out = ((2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0
                   + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1)
        else:
            raise ValueError(f"unknown interpolation {interpolation!r}")
    if rotation:
        out = out / np.linalg.norm(out)
    return np.array(out, dtype=np.float64)


def _node_trs(node):
    t = node.translation if node.translation is not None else [0.0, 0.0, 0.0]
    r = node.rotation if node.rotation is not None else [0.0, 0.0, 0.0, 1.0]
    s = node.scale if node.scale is not None else [1.0, 1.0, 1.0]
    return {"translation": np.array(t, float), "rotation": np.array(r, float), "scale": np.array(s, float)}


def node_globals(f: _File, animation_index=None, time=0.0) -> np.ndarray:
    """Global matrix of every node, (nodes, 4, 4), in the rest pose or an animation at ``time``."""
    nodes = f.gltf.nodes
    trs = [_node_trs(n) for n in nodes]
    animated = [set() for _ in nodes]
    if animation_index is not None:
        anim = f.gltf.animations[animation_index]
        for ch in anim.channels:
            if ch.target.node is None or ch.target.path not in ("translation", "rotation", "scale"):
                continue   # morph target weights and extension targets do not move nodes
            smp = anim.samplers[ch.sampler]
            times = f.accessor(smp.input)
            values = f.accessor(smp.output)
            values = values.reshape(len(values), -1)
            trs[ch.target.node][ch.target.path] = sample(times, values, smp.interpolation or "LINEAR",
                                                         ch.target.path, float(time))
            animated[ch.target.node].add(ch.target.path)
    local = []
    for i, n in enumerate(nodes):
        if n.matrix is not None and not animated[i]:
            local.append(np.array(n.matrix, dtype=np.float64).reshape(4, 4).T)  # column-major
        else:
            # An animated node cannot have a matrix (spec 3.11), so TRS is authoritative here.
            local.append(_trs(trs[i]["translation"], trs[i]["rotation"], trs[i]["scale"]))
    parent = [-1] * len(nodes)
    for i, n in enumerate(nodes):
        for c in n.children or []:
            parent[c] = i
    glob = [None] * len(nodes)

    def resolve(i):
        # Iterative walk up to the first resolved ancestor (no recursion limit on deep chains).
        chain = []
        while i >= 0 and glob[i] is None:
            chain.append(i)
            i = parent[i]
        for j in reversed(chain):
            glob[j] = local[j] if parent[j] < 0 else glob[parent[j]] @ local[j]

    for i in range(len(nodes)):
        resolve(i)
    return np.array(glob).reshape(len(nodes), 4, 4)


# --------------------------------------------------------------------------------------------------
# Skinning


def _attribute(prim, name):
    return getattr(prim.attributes, name, None)


def _sets(prim, prefix):
    out = []
    n = 0
    while True:
        idx = _attribute(prim, f"{prefix}_{n}")
        if idx is None:
            return out
        out.append(idx)
        n += 1


def skinned_primitives(path):
    """(node index, mesh primitive) for every triangle primitive of every skinned mesh node."""
    f = _File(path)
    out = []
    for i, node in enumerate(f.gltf.nodes):
        if node.mesh is None or node.skin is None:
            continue
        for prim in f.gltf.meshes[node.mesh].primitives:
            if (prim.mode if prim.mode is not None else _TRIANGLES) == _TRIANGLES:
                out.append((i, prim))
    return f, out


def reference_skin(path, animation_index=None, time=0.0, *, normalize=True, max_influences=None):
    """Skinned vertex positions of a glTF file, per the glTF 2.0 specification, in float64.

    path : .gltf or .glb file
    animation_index : int or None; None poses the nodes at their rest (node) transforms
    time : float seconds into the animation
    normalize : divide each vertex's weights by their sum over all sets. The spec requires weights that
        sum to 1; files that break this (assimp writes some) are skinned as viewers do, by renormalising.
    max_influences : None keeps every influence; k keeps each vertex's k largest weights (before
        normalising), to mirror a runtime limited to k influences
    returns (n, 3) float64: the POSITION data of every triangle primitive of every skinned mesh node,
        concatenated in node order then primitive order, each vertex as stored in the file
    """
    f, prims = skinned_primitives(path)
    if not prims:
        raise ValueError(f"{path}: no skinned triangle mesh")
    glob = node_globals(f, animation_index, time)
    out = []
    for node_index, prim in prims:
        skin = f.gltf.skins[f.gltf.nodes[node_index].skin]
        n_joints = len(skin.joints)
        if skin.inverseBindMatrices is not None:
            ibm = f.accessor(skin.inverseBindMatrices)
        else:
            ibm = np.broadcast_to(np.eye(4), (n_joints, 4, 4))
        joint_mats = np.array([glob[j] @ ibm[k] for k, j in enumerate(skin.joints)])
        pos = f.accessor(_attribute(prim, "POSITION"))
        joints = np.concatenate([f.accessor(a) for a in _sets(prim, "JOINTS")], axis=1)
        weights = np.concatenate([f.accessor(a) for a in _sets(prim, "WEIGHTS")], axis=1)
        if max_influences is not None and weights.shape[1] > max_influences:
            order = np.argsort(-weights, axis=1, kind="stable")[:, :max_influences]
            joints = np.take_along_axis(joints, order, axis=1)
            weights = np.take_along_axis(weights, order, axis=1)
        if normalize:
            total = weights.sum(axis=1, keepdims=True)
            weights = np.where(total > 0, weights / np.where(total > 0, total, 1.0), weights)
        homo = np.concatenate([pos, np.ones((len(pos), 1))], axis=1)
        skinned = np.zeros((len(pos), 4))
        for c in range(joints.shape[1]):
            skinned += weights[:, c, None] * np.einsum("nij,nj->ni", joint_mats[joints[:, c]], homo)
        out.append(skinned[:, :3])
    return np.concatenate(out, axis=0)


def bind_positions(path) -> np.ndarray:
    """POSITION data in the same order as ``reference_skin``, (n, 3) float64."""
    f, prims = skinned_primitives(path)
    return np.concatenate([f.accessor(_attribute(p, "POSITION")) for _, p in prims], axis=0)
