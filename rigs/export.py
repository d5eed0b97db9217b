"""glTF 2.0 exporter: ``Rig`` -> skinned .glb or .gltf.

The file holds one mesh with one triangle primitive (POSITION, the rig's attributes under the
names of ``_gltf_attributes``: NORMAL, TANGENT, TEXCOORD_n, COLOR_n, "_NAME", anything else as
"_NAME" mapped back in the extras; JOINTS_0, WEIGHTS_0, uint32 indices), the skeleton nodes in the
rig's order (so node ``i`` of the file is skeleton node ``i``), one skin whose joints are the bones
(a skeleton node that several bones share, as skins merged on loading do, is the joint of the
first; each other one gets a child node without transform, marked ``JOINT_OF`` in its extras,
which the loader folds back), a root mesh node without transform that carries the skin, one
scene, and one animation per clip.

Precision. glTF requires float32 for positions, weights, inverse bind matrices and keyframes;
node transforms are JSON numbers and keep float64. Hence:

* a rig loaded from a glTF file (whose data were float32 to begin with) saves and reloads to
  bit-identical arrays: vertices, faces, joints, weights, every skeleton array, every clip;
* a rig built in float64 (the capsule arm, a ``clip_from_poses`` clip, an edited skeleton)
  reloads bit-identical too, except its attributes (NORMAL, TEXCOORD_0, "_NAME", ...), which
  reload under their names to float32 rounding (relative 6e-8). So ``skin(loaded, loaded.pose(clip, t))`` is
  ``skin(rig, rig.pose(clip, t))`` exactly, and a posed tear stroke continues a saved slit.

Each float32 accessor of positions, weights, inverse bind matrices, key times and keyframe values
holds the float32 rounding of the float64 data (what every viewer reads); when that is not the
float64 value, two float32 residuals hold the rest, x == (hi + LO) + LO2 exactly (24 + 24 + 24
bits >= 53; ``_residuals.split``; exact for 0 and |x| >= 2^-97 ~ 6e-30, below that the residuals
underflow float32). Weights need them even when they are float32 values that do not sum to 1 in
float64 (the loader would renormalise them). The residuals are accessors named in the
``extras["cgaskin"]`` of the object that holds the data: the primitive (``POSITION_LO``/``_LO2``,
``WEIGHTS_0_LO``/``_LO2``), the skin (``INVERSE_BIND_LO``/``_LO2``) and each animation sampler
(``INPUT_LO``/``_LO2`` for its times, ``OUTPUT_LO``/``_LO2`` for its values). Samplers with the same
float64 key times share one input accessor and its residuals.

Layout for other readers (every file the CLI writes is opened in Blender 5.0 and three.js by
tests/clients). Blender's importer (io_scene_gltf2, blender/imp/mesh.py) keeps the names of the
application-specific "_NAME" attributes in a set and their arrays in a list, and concatenates
them in the set's order: when two of them differ in width (the tear's SCALAR ``_TEAR`` beside a
VEC4, or a user's VEC3 ``_FOO``) the import fails for some ``PYTHONHASHSEED`` values. Hence:

* the residuals are no vertex attributes but accessors named in ``extras["cgaskin"]`` (of the
  primitive, the skin, the samplers), which other readers ignore
  (earlier versions wrote ``_CGASKIN_WEIGHTS_0_LO`` attributes; the loader still reads them);
* the application attributes of one file all have one width, the widest: narrower ones are
  zero-padded and their own widths kept in ``extras["cgaskin"]["ATTRIBUTE_WIDTHS"]``, from which
  the loader trims them back (three.js reads any width; Blender then reads them all).
"""
from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pygltflib

from .._shared.warn import warn
from ..animation.clip import CHANNEL_PATHS, INTERPOLATIONS
from ..animation.rig import Rig
from ..animation.validate import EXACT_SUM_TOLERANCE, check_mesh
from ..errors import InvalidInputError, MissingFolderError, ModelWarning
from ._gltf_attributes import gltf_attribute_names
from ._gltf_constants import (ATTRIBUTE_NAMES, ATTRIBUTE_WIDTHS, EXTRAS_KEY, JOINT_OF, INPUT_RESIDUALS, INVERSE_BIND_RESIDUALS,
                              OUTPUT_RESIDUALS, POSITION_RESIDUALS, WEIGHT_RESIDUALS)
from ._residuals import split
from .gltf import trs_to_matrix

__all__ = ["save_gltf", "save_mesh"]

FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}


class _BinaryBuilder:
    """Accumulates one binary buffer and the bufferViews/accessors that describe it."""

    def __init__(self):
        self.blob = bytearray()
        self.views: list[pygltflib.BufferView] = []
        self.accessors: list[pygltflib.Accessor] = []

    def add(self, array: np.ndarray, component_type: int, width: int, *, target=None,
            min_max=False) -> int:
        """Append ``array`` (count, width) of the given component type; return its accessor index."""
        dtype = {FLOAT: "<f4", UNSIGNED_BYTE: "<u1", UNSIGNED_SHORT: "<u2", UNSIGNED_INT: "<u4"}[component_type]
        data = np.ascontiguousarray(array, dtype=dtype).reshape(-1, width)
        self.blob += b"\0" * (-len(self.blob) % 4)  # spec: accessors aligned to 4 bytes
        view = pygltflib.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=data.nbytes,
                                    target=target)
        self.blob += data.tobytes()
        self.views.append(view)
        accessor = pygltflib.Accessor(bufferView=len(self.views) - 1, byteOffset=0,
                                      componentType=component_type, count=len(data),
                                      type=TYPES[width])
        if min_max:
            # min/max must be the exact float32 values stored (float(float32) is exact in JSON)
            accessor.min = data.min(axis=0).astype(np.float64).tolist()
            accessor.max = data.max(axis=0).astype(np.float64).tolist()
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def _float32(array, what: str) -> np.ndarray:
    """float32 copy of ``array``; refuses values beyond float32 range (they would become inf)."""
    with np.errstate(over="ignore"):  # overflow is reported below, with the culprit's name
        out = np.asarray(array, dtype=np.float64).astype(np.float32)
    if not np.isfinite(out).all():
        raise InvalidInputError(f"{what} holds values that are not finite in float32 (|x| > 3.4e38 "
                                f"or NaN); glTF stores them as float32")
    return out


def _residuals(out: _BinaryBuilder, names, values, high: np.ndarray, width: int, force=False) -> dict:
    """{name: accessor} of the float64 ``values``' rounding residuals beside their float32 rounding
    ``high`` (``_residuals.split``), for ``extras["cgaskin"]``; {} when ``high`` already is
    ``values`` (and not ``force``): the residuals would be zeros."""
    if not force and np.array_equal(high, values):
        return {}
    return {name: out.add(residual, FLOAT, width) for name, residual in zip(names, split(values, high))}


def _check_skeleton(rig: Rig) -> None:
    sk = rig.skeleton
    j, b = sk.n_nodes, sk.n_bones
    shapes = {"parents": (sk.parents, (j,)), "rest_translations": (sk.rest_translations, (j, 3)),
              "rest_rotations": (sk.rest_rotations, (j, 4)), "rest_scales": (sk.rest_scales, (j, 3)),
              "rest_matrices": (sk.rest_matrices, (j, 4, 4)), "bone_nodes": (sk.bone_nodes, (b,)),
              "inverse_bind": (sk.inverse_bind, (b, 4, 4))}
    for name, (array, shape) in shapes.items():
        if np.shape(array) != shape:
            raise InvalidInputError(f"skeleton.{name} has shape {np.shape(array)}, expected {shape}")
        if not np.isfinite(array).all():
            raise InvalidInputError(f"skeleton.{name} holds non-finite values")
    parents = np.asarray(sk.parents)
    if ((parents >= np.arange(j)) | (parents < -1)).any():
        bad = int(np.flatnonzero((parents >= np.arange(j)) | (parents < -1))[0])
        raise InvalidInputError(f"skeleton node {bad} has parent {int(parents[bad])}: parents must "
                                f"precede their children (parents[i] < i, -1 for roots)")
    bones = np.asarray(sk.bone_nodes)
    if b == 0:
        raise InvalidInputError("the skeleton has no bones: a glTF skin needs at least one joint")
    if ((bones < 0) | (bones >= j)).any():
        raise InvalidInputError(f"skeleton.bone_nodes must index the {j} nodes, got {bones.tolist()}")


def save_gltf(rig: Rig, path) -> Path:
    """Write ``rig`` as skinned glTF 2.0: binary ``.glb`` or ``.gltf`` with an embedded buffer.

    Parameters
    ----------
    rig : Rig
        vertices (n, 3), faces (m, 3), joints (n, 4) bone indices, weights (n, 4); attributes
        (n, c) arrays are written as vertex attributes and reload under their names
        (``_gltf_attributes``: NORMAL, TANGENT, TEXCOORD_n, COLOR_n, "_NAME", others renamed
        "_NAME" in the file and mapped back by the extras).
    path : str or os.PathLike
        Ends in .glb or .gltf.

    Returns
    -------
    Path of the written file.

    Round trips (see the module docstring): positions, weights, inverse bind matrices and
    keyframes reload exactly (float32 + residuals where float32 alone is not exact); attributes go
    through float32, exact for rigs loaded from glTF, float32-rounding for float64 ones. Skeleton nodes
    whose ``rest_matrices`` differ from their TRS (matrix nodes, shear) are written as matrices,
    unless a clip animates them (glTF allows only TRS on animated nodes).

    Raises
    ------
    InvalidInputError
        Unsupported extension, inconsistent arrays, more than 65536 bones, values beyond float32.
    MissingFolderError
        The folder of ``path`` does not exist (a ``FileNotFoundError`` too).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".glb", ".gltf"):
        raise InvalidInputError(f"cannot write {path.name}: save_gltf writes .glb or .gltf")
    _check_folder(path)
    _check_skeleton(rig)
    sk = rig.skeleton
    n_bones = sk.n_bones
    if n_bones > 65536:
        raise InvalidInputError(f"{n_bones} bones: glTF joints are at most unsigned short (65536 bones)")
    vertices, faces, joints, weights = check_mesh(rig.vertices, rig.faces, rig.joints, rig.weights,
                                                  n_bones=n_bones, source=rig.name)
    if len(faces) == 0:
        raise InvalidInputError("the rig has no faces: glTF needs at least one triangle")

    out = _BinaryBuilder()
    positions = _float32(vertices, "vertices")
    attributes = {"POSITION": out.add(positions, FLOAT, 3, target=ARRAY_BUFFER, min_max=True)}
    # float64 positions = (hi + lo) + lo2 exactly (in the extras: see the module docstring): a torn
    # model saved and loaded again has the exact positions its next stroke continues from
    ours = _residuals(out, POSITION_RESIDUALS, vertices, positions, 3)
    extras = {EXTRAS_KEY: ours} if ours else {}
    _write_attributes(rig.attributes, len(vertices), out, attributes, extras)
    joint_type = UNSIGNED_BYTE if n_bones <= 256 else UNSIGNED_SHORT
    attributes["JOINTS_0"] = out.add(joints, joint_type, 4, target=ARRAY_BUFFER)
    high = _float32(weights, "weights")
    attributes["WEIGHTS_0"] = out.add(high, FLOAT, 4, target=ARRAY_BUFFER)
    reloads_exactly = (np.array_equal(high, weights)
                       and (np.abs(high.astype(np.float64).sum(axis=1) - 1) <= EXACT_SUM_TOLERANCE).all())
    if not reloads_exactly:  # float64 weights = (hi + lo) + lo2 exactly
        extras.setdefault(EXTRAS_KEY, {}).update(_residuals(
            out, [name.format(0) for name in WEIGHT_RESIDUALS], weights, high, 4, force=True))
    indices = out.add(faces.reshape(-1), UNSIGNED_INT, 1, target=ELEMENT_ARRAY_BUFFER)
    # the spec stores matrices column-major; float64 matrices = (hi + lo) + lo2 exactly, so that a
    # posed surface (a posed tear's next stroke) is the same after save and load
    ibm64 = np.transpose(np.asarray(sk.inverse_bind, dtype=np.float64), (0, 2, 1))
    ibm32 = _float32(ibm64, "inverse bind matrices")
    ibm = out.add(ibm32, FLOAT, 16)
    ibm_residuals = _residuals(out, INVERSE_BIND_RESIDUALS, ibm64, ibm32, 16)

    animations, animated = _animations(rig, out)
    nodes = _skeleton_nodes(rig, animated)
    joints = _joint_nodes(rig, nodes)
    mesh_node = len(nodes)
    nodes.append(pygltflib.Node(name=rig.name, mesh=0, skin=0))  # root, no transform: ignored anyway
    roots = [i for i in range(sk.n_nodes) if sk.parents[i] == -1] + [mesh_node]

    primitive = pygltflib.Primitive(attributes=pygltflib.Attributes(**attributes), indices=indices,
                                    mode=pygltflib.TRIANGLES, extras=extras)
    gltf = pygltflib.GLTF2(
        asset=pygltflib.Asset(generator="cgaskin", version="2.0"),
        scene=0,
        scenes=[pygltflib.Scene(nodes=roots)],
        nodes=nodes,
        meshes=[pygltflib.Mesh(name=rig.name, primitives=[primitive])],
        skins=[pygltflib.Skin(joints=joints, inverseBindMatrices=ibm,
                              extras={EXTRAS_KEY: ibm_residuals} if ibm_residuals else {})],
        animations=animations,
        accessors=out.accessors,
        bufferViews=out.views,
        buffers=[pygltflib.Buffer(byteLength=len(out.blob))],
    )
    return _write(gltf, out.blob, path)


def _write_attributes(rig_attributes: dict, n: int, out: _BinaryBuilder, attributes: dict, extras: dict) -> None:
    """Add the rig's (n, c) attributes to the primitive's ``attributes`` under the names of
    ``_gltf_attributes.gltf_attribute_names`` (renamed ones mapped back in ``extras``), all
    application attributes at one width (zero-padded to the widest, the true widths in
    ``extras``; see the module docstring)."""
    arrays, renamed = gltf_attribute_names(rig_attributes, n)
    written = {name: _float32(values, f"attribute {renamed.get(name, name)!r}")
               for name, values in arrays.items()}
    if renamed:
        extras.setdefault(EXTRAS_KEY, {})[ATTRIBUTE_NAMES] = renamed
    widths = {name: values.shape[1] for name, values in written.items() if name.startswith("_")}
    common = max(widths.values(), default=0)
    if len(set(widths.values())) > 1:
        extras.setdefault(EXTRAS_KEY, {})[ATTRIBUTE_WIDTHS] = {
            name: width for name, width in widths.items() if width < common}
    for name, values in written.items():
        if name in widths and widths[name] < common:
            values = np.pad(values, ((0, 0), (0, common - widths[name])))
        attributes[name] = out.add(values, FLOAT, values.shape[1], target=ARRAY_BUFFER)


def _check_folder(path: Path) -> None:
    """``MissingFolderError`` naming the folder of ``path`` when it is no folder (checked before the
    file is made: Python's own error names the file, not the folder that is missing)."""
    folder = path.parent
    if not folder.is_dir():
        what = "no such folder" if not folder.exists() else "not a folder"
        raise MissingFolderError(f"cannot write {path.name}: {folder}: {what}; make it first "
                                 f"(mkdir -p {folder}) or write the file elsewhere")


def _write(gltf: pygltflib.GLTF2, blob: bytearray, path: Path) -> Path:
    """Write ``gltf`` with its one buffer ``blob``: GLB chunk or embedded base64 by extension."""
    if path.suffix.lower() == ".glb":
        gltf.set_binary_blob(bytes(blob))
        gltf.save_binary(str(path))
    else:
        gltf.buffers[0].uri = ("data:application/octet-stream;base64,"
                               + base64.b64encode(bytes(blob)).decode("ascii"))
        path.write_text(gltf.gltf_to_json(), encoding="utf-8")
    return path


def save_mesh(vertices, faces, path, normals=None, name: str = "mesh") -> Path:
    """Write a static triangle mesh (e.g. a skinned pose) as .glb or .gltf, without skin.

    vertices : (n, 3) float ; faces : (m, 3) int ; normals : optional (n, 3) float
    MissingFolderError (a FileNotFoundError) when the folder of ``path`` does not exist.
    """
    path = Path(path)
    if path.suffix.lower() not in (".glb", ".gltf"):
        raise InvalidInputError(f"cannot write {path.name}: save_mesh writes .glb or .gltf")
    _check_folder(path)
    vertices = _float32(vertices, "vertices")
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidInputError(f"vertices must have shape (n, 3), got {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0 or faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidInputError(f"faces must be a non-empty (m, 3) array of indices below {len(vertices)}")
    out = _BinaryBuilder()
    attributes = {"POSITION": out.add(vertices, FLOAT, 3, target=ARRAY_BUFFER, min_max=True)}
    if normals is not None:
        attributes["NORMAL"] = out.add(_float32(normals, "normals"), FLOAT, 3, target=ARRAY_BUFFER)
    indices = out.add(faces.reshape(-1), UNSIGNED_INT, 1, target=ELEMENT_ARRAY_BUFFER)
    primitive = pygltflib.Primitive(attributes=pygltflib.Attributes(**attributes), indices=indices,
                                    mode=pygltflib.TRIANGLES)
    gltf = pygltflib.GLTF2(
        asset=pygltflib.Asset(generator="cgaskin", version="2.0"), scene=0,
        scenes=[pygltflib.Scene(nodes=[0])], nodes=[pygltflib.Node(name=name, mesh=0)],
        meshes=[pygltflib.Mesh(name=name, primitives=[primitive])],
        accessors=out.accessors, bufferViews=out.views, buffers=[pygltflib.Buffer(byteLength=len(out.blob))])
    return _write(gltf, out.blob, path)


def _skeleton_nodes(rig: Rig, animated: set) -> list:
    """One glTF node per skeleton node, same order; TRS, or the exact matrix where they differ."""
    sk = rig.skeleton
    children = [[] for _ in range(sk.n_nodes)]
    for i, p in enumerate(sk.parents):
        if p >= 0:
            children[p].append(i)
    nodes = []
    for i in range(sk.n_nodes):
        t, q, s = sk.rest_translations[i], sk.rest_rotations[i], sk.rest_scales[i]
        matrix = np.asarray(sk.rest_matrices[i], dtype=np.float64)
        node = pygltflib.Node(name=sk.names[i], children=children[i])
        # exact comparison: the loader computes TRS-node matrices with this very function, so a
        # TRS node reloads bit-identical and anything else (a matrix node) keeps its matrix
        if np.array_equal(matrix, trs_to_matrix(t, q, s)) or i in animated:
            if i in animated and not np.allclose(matrix, trs_to_matrix(t, q, s), rtol=0, atol=1e-9):
                warn(f"{rig.name}: node {sk.names[i]!r} is animated, so glTF requires TRS, "
                     f"but its rest matrix is not a TRS (shear?); wrote the TRS", ModelWarning)
            if not np.array_equal(t, [0, 0, 0]):
                node.translation = [float(x) for x in t]
            if not np.array_equal(q, [0, 0, 0, 1]):
                node.rotation = [float(x) for x in q]
            if not np.array_equal(s, [1, 1, 1]):
                node.scale = [float(x) for x in s]
        else:
            node.matrix = [float(x) for x in matrix.T.reshape(-1)]  # column-major
        nodes.append(node)
    return nodes


def _joint_nodes(rig: Rig, nodes: list) -> list[int]:
    """The file node of each bone (the skin's joints, which glTF wants unique).

    A skeleton node that several bones share (skins merged on loading, each with its own inverse
    bind matrix) is the joint of its first bone; each further bone gets a child node without
    transform, so that it moves with the node in every pose and clip, in every reader, and its
    extras name the node it duplicates (``JOINT_OF``) so that the loader folds it back.
    """
    names = rig.skeleton.names
    joints, seen = [], set()
    for b, k in enumerate(int(k) for k in rig.skeleton.bone_nodes):
        if k not in seen:
            seen.add(k)
            joints.append(k)
            continue
        nodes[k].children.append(len(nodes))
        nodes.append(pygltflib.Node(name=f"{names[k]}.bone{b}", extras={EXTRAS_KEY: {JOINT_OF: k}}))
        joints.append(len(nodes) - 1)
    return joints


def _animations(rig: Rig, out: _BinaryBuilder):
    """glTF animations of the rig's clips, and the set of skeleton nodes they animate."""
    animations, animated = [], set()
    for clip in rig.clips:
        samplers, channels, inputs = [], [], {}
        for c, ch in enumerate(clip.channels):
            where = f"clip {clip.name!r} channel {c}"
            if ch.path not in CHANNEL_PATHS or ch.interpolation not in INTERPOLATIONS:
                raise InvalidInputError(f"{where}: path {ch.path!r} / interpolation {ch.interpolation!r} "
                                        f"is not glTF's")
            if not 0 <= ch.node < rig.skeleton.n_nodes:
                raise InvalidInputError(f"{where} targets node {ch.node}, outside the skeleton")
            width = CHANNEL_PATHS[ch.path]
            times64 = np.asarray(ch.times, dtype=np.float64).reshape(-1)
            times = _float32(times64, f"{where} times")
            if len(times) == 0 or (np.diff(times) <= 0).any():
                raise InvalidInputError(f"{where}: key times must increase strictly (in float32)")
            per_key = 3 if ch.interpolation == "CUBICSPLINE" else 1
            values = np.asarray(ch.values, dtype=np.float64)
            if values.shape != ((len(times), 3, width) if per_key == 3 else (len(times), width)):
                raise InvalidInputError(f"{where}: values have shape {values.shape} for {len(times)} "
                                        f"{ch.interpolation} keys of {ch.path}")
            # channels of one clip usually share their key times: store each set once, with its
            # residuals (float64 times = (hi + lo) + lo2 exactly), keyed by the float64 times
            key = times64.tobytes()
            if key not in inputs:
                inputs[key] = (out.add(times, FLOAT, 1, min_max=True),  # the spec requires min/max
                               _residuals(out, INPUT_RESIDUALS, times64, times, 1))
            input_, ours = inputs[key]
            values = values.reshape(-1, width)
            high = _float32(values, f"{where} values")
            output = out.add(high, FLOAT, width)
            ours = {**ours, **_residuals(out, OUTPUT_RESIDUALS, values, high, width)}
            samplers.append(pygltflib.AnimationSampler(input=input_, output=output,
                                                       interpolation=ch.interpolation,
                                                       extras={EXTRAS_KEY: ours} if ours else {}))
            channels.append(pygltflib.AnimationChannel(
                sampler=len(samplers) - 1,
                target=pygltflib.AnimationChannelTarget(node=int(ch.node), path=ch.path)))
            animated.add(int(ch.node))
        if not channels:
            warn(f"{rig.name}: clip {clip.name!r} has no channels; glTF animations need at "
                 f"least one, so it is not written", ModelWarning)
            continue
        animations.append(pygltflib.Animation(name=clip.name, samplers=samplers, channels=channels))
    return animations, animated
