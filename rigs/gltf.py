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
from which they are rebuilt exactly; other readers ignore them and use the float32 WEIGHTS_0. The
float64 positions' residuals are in the primitive's ``extras["cgaskin"]`` (accessor indices,
``POSITION_RESIDUALS``), so that a torn model saved and loaded again has the exact positions its
next stroke continues from.

This module is the driver; the work is done by private modules, one topic each:
``_gltf_container`` (file bytes -> document), ``_gltf_document`` (``_GltfFile``: checked access
to the JSON, buffers and accessors), ``_gltf_nodes`` (hierarchy, node transforms, skins,
skeleton), ``_gltf_mesh`` (primitives, merged mesh), ``_gltf_clips`` (animations) and
``_gltf_constants`` (the tables).
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..algebra.transforms import matrix_to_quat, matrix_to_trs, quat_to_matrix, trs_matrix
from ..animation.rig import Rig
from ..animation.validate import check_mesh
from ..errors import CgaskinError, InvalidInputError, ModelFormatError, NoSkinError
from ._gltf_clips import _read_clips
from ._gltf_constants import (AFFINE_TOLERANCE, COMPONENT_DTYPES, COMPONENT_NAMES, GLB_BIN_CHUNK,
                              GLB_JSON_CHUNK, GLB_MAGIC, INTEGER_INDEX_TYPES, MAX_BUFFERLESS_COMPONENTS,
                              MODE_NAMES, NORMALIZED_DIVISORS, QUAT_UNIT_TOLERANCE, TYPE_SHAPES,
                              UNSUPPORTED_EXTENSIONS, WEIGHT_RESIDUALS, EXTRAS_KEY, POSITION_RESIDUALS)
from ._gltf_container import _read_document
from ._gltf_document import _GltfFile
from ._gltf_mesh import _merge_primitives, _read_primitive
from ._gltf_nodes import _build_skeleton, _parents, _read_skins, _scene_nodes

__all__ = ["load_gltf", "trs_to_matrix", "matrix_to_trs", "quat_to_matrix", "matrix_to_quat"]


# --- transforms (shared with the exporter) -----------------------------------------------------

def trs_to_matrix(translation, rotation, scale) -> np.ndarray:
    """The glTF local matrix T @ R @ S (see ``cgaskin.algebra.transforms.trs_matrix``).

    translation : (3,) float; rotation : (4,) float unit quaternion (x, y, z, w); scale : (3,) float
    returns : (4, 4) float64
    """
    return trs_matrix(translation, rotation, scale)


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
    """The rig of a read document: scene, skins, merged mesh (checked by ``check_mesh``), skeleton,
    clips. Every problem raises ``ModelFormatError`` (``NoSkinError`` when nothing is skinned)."""
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
    vertices, faces, joints, weights, attributes = _merge_primitives(f, skinned, slot_maps)

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            vertices, faces, joints, weights = check_mesh(vertices, faces, joints, weights,
                                                          n_bones=n_bones, source=f.path.name)
    except InvalidInputError as exc:
        raise ModelFormatError(str(exc)) from None
    for warning in caught:  # re-issued so that they point at the caller of load, not in here
        f.warn(str(warning.message), prefix=False)

    skeleton, node_to_skeleton = _build_skeleton(f, bone_file_nodes, inverse_bind, parents)
    clips = _read_clips(f, node_to_skeleton)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights, skeleton=skeleton,
               clips=clips, attributes=attributes, name=f.path.stem)
