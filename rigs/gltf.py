"""glTF 2.0 loader: a .glb/.gltf file, skinned or not -> ``Rig``.

pygltflib parses the JSON into dataclasses; everything else is decoded here with numpy, following
the glTF 2.0 specification (section 3.6 "Binary data storage", 3.7 "Geometry", 3.8 "Transforms and
skinning", 3.11 "Animations"):

* accessors of every component type, ``normalized`` integers, ``byteStride``, accessor and
  bufferView ``byteOffset``, matrix column padding, sparse accessors, accessors without bufferView;
* buffers from a GLB binary chunk, ``data:`` URIs and external files next to the .gltf;
* all triangle primitives (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) of all mesh nodes of the
  default scene, merged into one mesh; JOINTS_n/WEIGHTS_n sets reduced to 4 influences;
* every skin used, merged into one skeleton (joints plus all their ancestors); a mesh node
  without a skin is a rigid bone of its own (``_gltf_rigid``);
* TRS and matrix node transforms, animations of skeleton nodes.

A file is untrusted input: pygltflib checks neither types nor ranges, so every index, count and
offset is checked here before use, and every problem becomes a ``ModelFormatError`` that names the
file and the offending object (``NoSkinError`` when the file is valid but holds no mesh). The
loader never returns NaN or infinity.

Precision: glTF stores positions, weights, inverse bind matrices and keyframes as float32; they are
returned as float64 holding exactly the float32 values, except the weights, which are renormalised
in float64 so that every row sums to 1 (``check_mesh``). Files written by ``save_gltf`` carry the
float64 data's rounding residuals as accessors named in ``extras["cgaskin"]`` (``_residuals``):
the primitive's for positions and weights (``POSITION_RESIDUALS``, ``WEIGHT_RESIDUALS``; earlier
versions kept the weights' in "_CGASKIN_WEIGHTS_n_LO" attributes, still read), the skin's for the
inverse bind matrices (``INVERSE_BIND_RESIDUALS``) and each animation sampler's for its key times
and values (``INPUT_RESIDUALS``, ``OUTPUT_RESIDUALS``). The loader adds them back, so a float64
rig saved and loaded again has exactly its positions, weights, bind matrices and keyframes: a
torn model, posed or not, is the same surface and its next stroke continues the slit. Other
readers ignore the extras and use the float32 data.

This module is the driver; the work is done by private modules, one topic each:
``_gltf_container`` (file bytes -> document), ``_gltf_document`` (``_GltfFile``: checked access
to the JSON, buffers and accessors), ``_gltf_nodes`` (hierarchy, node transforms, skins,
skeleton), ``_gltf_mesh`` (primitives, merged mesh), ``_gltf_rigid`` (meshes without a skin,
and the skeleton and mesh of both kinds), ``_gltf_clips`` (animations) and
``_gltf_attributes`` (vertex attributes other than positions and skinning, both ways) and
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
from ._gltf_nodes import _mesh_nodes, _parents, _scene_nodes
from ._gltf_rigid import _skeleton_and_mesh

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
    """Load a glTF 2.0 file (.glb or .gltf), skinned or not, as a ``Rig``.

    Every mesh node of the default scene (all nodes when the file has no scene) contributes all
    its triangle primitives, merged into one mesh: first the skinned ones (node with ``mesh`` and
    ``skin``) in scene order, then the unskinned ones in scene order.

    * Skinned mesh nodes: the vertices as stored (the bind pose), their joints and weights; the
      mesh nodes' own transforms are ignored (glTF skinning semantics).
    * Mesh nodes without a skin (a static organ, a prop, a scanned mesh) are *rigid bones*: each
      such node is a bone of the skeleton, its vertices are put into the bind pose
      ``B · v_local`` with inverse bind matrix ``B⁻¹`` and weight 1 on that bone. ``B`` is the
      node's global transform with every skin joint at its bind pose (``Pose.bind``'s rule); in a
      file without skins that is the rest (node) global transform, so ``rig.vertices`` is the mesh
      as a viewer shows it, ``skin(rig, rig.rest_pose())`` returns it, and animations of the mesh
      nodes or their ancestors play. Mirrored nodes (negative determinant) get their faces' winding
      reversed so that outward stays outward; NORMAL is transformed with the inverse transpose; a
      node with a singular transform (scale 0) keeps its local vertices with an identity inverse
      bind matrix, with a warning. In a file with both kinds the
      rigid meshes come along (eyes, props, armour attached to a character move with the joint
      they hang from, as in a viewer).

    The skeleton holds the joints of every skin used, every rigid mesh node, and all their
    ancestors. Influences beyond 4 are reduced to the largest 4 and weight rows renormalised (with
    a warning, see ``check_mesh``).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Rig
        vertices (n, 3) float64, faces (m, 3) int64, joints (n, 4) int64, weights (n, 4) float64
        (rows sum to 1 in float64), skeleton, clips (one per animation, named ``animation.name`` or
        ``clip{i}``; an animation with NaN/infinite/unordered keys is dropped with a warning),
        attributes NORMAL (n, 3), TANGENT (n, 4), TEXCOORD_n (n, 2), COLOR_n (n, 3 or 4) and
        application-specific "_NAME" (n, c) when every primitive has them (``_gltf_attributes``),
        name = the file's stem.

    Raises
    ------
    ModelFormatError
        The file is missing, truncated, not glTF 2.0, or inconsistent (the message says where).
    NoSkinError
        The file is valid but its scene holds no mesh (or no triangle of one).
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
    """The rig of a read document: the scene's mesh nodes, skeleton and merged mesh
    (``_gltf_rigid``: skinned nodes and rigid ones), checked by ``check_mesh``, clips. Every problem
    raises ``ModelFormatError`` (``NoSkinError`` when the scene holds no triangle mesh)."""
    parents = _parents(f)
    skinned, rigid = _mesh_nodes(f, _scene_nodes(f, parents))
    if not skinned and not rigid:
        raise f.error("holds no mesh (no node of its scene has one): nothing to load", cls=NoSkinError)
    skeleton, node_to_skeleton, mesh = _skeleton_and_mesh(f, parents, skinned, rigid)
    vertices, faces, joints, weights, attributes = mesh
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            vertices, faces, joints, weights = check_mesh(vertices, faces, joints, weights,
                                                          n_bones=skeleton.n_bones, source=f.path.name)
    except InvalidInputError as exc:
        raise ModelFormatError(str(exc)) from None
    for warning in caught:  # re-issued so that they point at the caller of load, not in here
        f.warn(str(warning.message), prefix=False)
    clips = _read_clips(f, node_to_skeleton)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights, skeleton=skeleton,
               clips=clips, attributes=attributes, name=f.path.stem)
