"""Meshes without a skin (a static organ, a prop, a scan): every such mesh node becomes a rigid bone.

glTF draws a mesh node without ``skin`` at the node's global transform G (spec 3.5.3); a node that
is a skin joint, or the child of one, moves with that joint when the skin is animated. The loader
keeps exactly this behaviour inside the one skinning model cgaskin has:

* each unskinned mesh node with triangle primitives is a *bone* of the skeleton (the skeleton also
  holds all its ancestors, so that animations of parent nodes move it, as in a viewer);
* its vertices are stored in the bind pose, ``B · v_local``, with inverse bind matrix ``B⁻¹``,
  joints = that bone with weight 1. B is the node's *bind global*: the inverse of its inverse
  bind matrix for a node that is a skin joint, else ``B(parent) · local`` (``local`` alone for a
  root), the same rule as ``Pose.bind``. In a file without any skin B is the rest (node) global
  transform, so ``rig.vertices`` is what a viewer shows at rest and ``skin(rig, rig.rest_pose())``
  returns them again; in a file with skins, a prop below a joint lies where the skinned mesh's
  bind pose puts that joint, so the stored mesh is one consistent body;
* NORMAL goes to the bind pose with the inverse transpose (``n · B⁻¹``, renormalised), TANGENT
  with ``B`` itself (renormalised, its sign w flipped by a mirror);
* a node whose global transform mirrors (negative determinant) has its faces' winding reversed:
  glTF says the determinant selects the winding order of a triangle primitive, and cgaskin's faces
  are counter-clockwise in the bind pose, so outward stays outward;
* a node whose bind global is singular (a scale of 0: the mesh is invisible, as for a prop that a
  clip scales up) keeps its vertices in its own coordinates with an identity inverse bind matrix
  (skinning is still ``G · v_local`` in every pose), with a warning;
* a mesh used by several nodes is loaded once per node, as it is drawn.

Skinned mesh nodes come first in the merged mesh (as ``_merge_primitives`` merges them), then the
rigid ones in scene order. Unused JOINTS_n/WEIGHTS_n of an unskinned primitive are ignored.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import NoSkinError
from ._gltf_document import _GltfFile
from ._gltf_mesh import _merge_primitives, _read_primitive
from ._gltf_nodes import _build_skeleton, _read_skins

__all__ = ["_skeleton_and_mesh"]


def _skeleton_and_mesh(f: _GltfFile, parents: list[int], skinned: list[tuple[int, int]],
                       rigid: list[int]):
    """The skeleton and the merged mesh of the skinned mesh nodes and the rigid ones.

    skinned : [(file node, skin)] in scene order; rigid : file nodes with a mesh and no skin
    returns : (Skeleton, {file node: skeleton node},
               (vertices (n, 3), faces (m, 3), joints (n, k), weights (n, k), attributes))
    Raises NoSkinError when no node holds a triangle mesh, ModelFormatError for broken data.
    """
    skin_bones, skin_ibm, slot_maps = _read_skins(f, sorted({s for _, s in skinned}))
    parts = []
    if skinned:
        try:
            merged = _merge_primitives(f, skinned, slot_maps)
        except NoSkinError:
            if not rigid:
                raise
        else:
            parts.append(dict(zip(("positions", "faces", "joints", "weights", "attributes"), merged)))
    rigid_parts = _read_rigid(f, rigid)
    if not parts and not rigid_parts:
        raise f.error(f"holds no triangle mesh ({len(skinned) + len(rigid)} mesh node(s), none with "
                      f"triangles)",
                      cls=NoSkinError)

    candidates = list(dict.fromkeys(node for node, _ in rigid_parts))
    ibm = np.concatenate([skin_ibm, np.broadcast_to(np.eye(4), (len(candidates), 4, 4))])
    skeleton, node_to_skeleton = _build_skeleton(f, list(skin_bones) + candidates, ibm, parents)
    if not rigid_parts:                       # skinned meshes only: the skins' bones as they are
        return skeleton, node_to_skeleton, _concatenate(f, parts)
    skin_nodes = skeleton.bone_nodes[:len(skin_bones)]
    bind = _bind_globals(skeleton, skin_nodes, skin_ibm)

    bone_nodes, inverse_bind = list(skin_nodes), list(skin_ibm)
    bone_of, seen = {}, set()                 # skeleton node -> bone holding its rigid meshes
    for b, node in enumerate(skin_nodes):     # a joint's meshes use its first bone, as ``bind`` does
        if int(node) not in seen:
            seen.add(int(node))
            if _inverse(skin_ibm[b]) is not None:
                bone_of[int(node)] = b
    for node, part in rigid_parts:
        k = node_to_skeleton[node]
        if k not in bone_of:
            inverse = _inverse(bind[k])
            if inverse is None:
                f.warn(f"node {node} ({skeleton.names[k]!r}) has a singular transform (a scale of 0): "
                       f"its mesh is stored in the node's own coordinates (inverse bind matrix "
                       f"identity) and shows where a pose or clip scales it up")
                bind[k], inverse = np.eye(4), np.eye(4)
            bone_of[k] = len(bone_nodes)
            bone_nodes.append(k)
            inverse_bind.append(inverse)
        parts.append(_to_bind_pose(part, bind[k], inverse_bind[bone_of[k]], bone_of[k]))
    skeleton = replace(skeleton, bone_nodes=np.array(bone_nodes, dtype=np.int64),
                       inverse_bind=np.array(inverse_bind, dtype=np.float64).reshape(-1, 4, 4))
    return skeleton, node_to_skeleton, _concatenate(f, parts)


def _read_rigid(f: _GltfFile, rigid: list[int]) -> list[tuple[int, dict]]:
    """[(file node, primitive)] of every triangle primitive of the rigid mesh nodes, node-local."""
    nodes = f.items("nodes")
    out, skipped = [], []
    for i in rigid:
        m = nodes[i].mesh
        for p, prim in enumerate(f.items("meshes")[m].primitives or []):
            part = _read_primitive(f, m, p, prim, skinned=False)
            if isinstance(part, str):
                skipped.append(part)
            else:
                out.append((i, part))
    if skipped:
        f.warn(f"skipped {len(skipped)} primitives of unskinned meshes that are not triangles "
               f"({', '.join(sorted(set(skipped)))})")
    return out


def _inverse(m: np.ndarray) -> np.ndarray | None:
    """The inverse of an affine (4, 4) matrix, None when it is singular or not finite."""
    if not np.isfinite(m).all() or np.linalg.det(m[:3, :3]) == 0:
        return None
    inverse = np.linalg.inv(m)
    if not np.isfinite(inverse).all():
        return None
    inverse[3] = (0.0, 0.0, 0.0, 1.0)
    return inverse


def _bind_globals(skeleton, skin_nodes, skin_ibm) -> np.ndarray:
    """(j, 4, 4) bind global of every skeleton node: the inverse of its first inverse bind matrix
    for a skin joint, else parent's bind global @ rest local (``Pose.bind``'s rule); the rest
    globals (root first products) when there is no skin."""
    first = {}
    for node, matrix in zip(skin_nodes, skin_ibm):
        first.setdefault(int(node), matrix)
    out = np.empty((skeleton.n_nodes, 4, 4))
    for i, p in enumerate(skeleton.parents):
        inverse = _inverse(first[i]) if i in first else None
        if inverse is not None:
            out[i] = inverse
        else:
            out[i] = skeleton.rest_matrices[i] if p < 0 else out[p] @ skeleton.rest_matrices[i]
    return out


def _to_bind_pose(part: dict, bind: np.ndarray, inverse_bind: np.ndarray, bone: int) -> dict:
    """A node-local primitive moved to the bind pose and weighted 1 to ``bone``."""
    a = bind[:3, :3]
    faces = part["faces"]
    if np.linalg.det(a) < 0:              # mirrored: reverse the winding so outward stays outward
        faces = faces[:, [0, 2, 1]]
    attributes = dict(part["attributes"])
    if "NORMAL" in attributes:            # the inverse transpose: n' = B^-T n, as rows n @ B^-1
        normals = attributes["NORMAL"] @ inverse_bind[:3, :3]
        length = np.linalg.norm(normals, axis=1, keepdims=True)
        attributes["NORMAL"] = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    if "TANGENT" in attributes:           # a direction in the surface: x' = B x, renormalised; the
        tangents = attributes["TANGENT"].copy()  # sign w flips with a mirror, as the bitangent does
        xyz = tangents[:, :3] @ a.T
        length = np.linalg.norm(xyz, axis=1, keepdims=True)
        tangents[:, :3] = np.divide(xyz, length, out=np.zeros_like(xyz), where=length > 0)
        tangents[:, 3] *= np.sign(np.linalg.det(a)) or 1.0
        attributes["TANGENT"] = tangents
    n = len(part["positions"])
    return {"positions": part["positions"] @ a.T + bind[:3, 3], "faces": faces,
            "joints": np.full((n, 1), bone, dtype=np.int64), "weights": np.ones((n, 1)),
            "attributes": attributes}


def _concatenate(f: _GltfFile, parts: list[dict]):
    """One mesh of several parts: vertices (n, 3), faces (m, 3), joints/weights (n, k) zero-padded
    to the widest part, the attributes that every part has (others dropped with a warning)."""
    if sum(len(p["faces"]) for p in parts) == 0:
        raise f.error("the meshes hold no triangle (all primitives are empty or degenerate)")
    if len(parts) == 1:
        p = parts[0]
        return p["positions"], p["faces"], p["joints"], p["weights"], p["attributes"]
    offsets = np.cumsum([0] + [len(p["positions"]) for p in parts])
    vertices = np.concatenate([p["positions"] for p in parts])
    faces = np.concatenate([p["faces"] + off for p, off in zip(parts, offsets)])
    width = max(p["weights"].shape[1] for p in parts)

    def padded(key, dtype):
        return np.concatenate([np.pad(p[key], ((0, 0), (0, width - p[key].shape[1]))) for p in parts]).astype(dtype)

    attributes = {}
    for name in dict.fromkeys(name for p in parts for name in p["attributes"]):
        have = [name in p["attributes"] for p in parts]
        if all(have):
            attributes[name] = np.concatenate([p["attributes"][name] for p in parts])
        else:
            f.warn(f"dropped attribute {name}: only {sum(have)} of {len(parts)} merged meshes have it")
    return vertices, faces, padded("joints", np.int64), padded("weights", np.float64), attributes
