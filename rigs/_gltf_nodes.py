"""Node hierarchy and skins of a glTF document (spec 3.5 "Nodes and hierarchy", 3.8 "Skins").

Parents (a tree, no cycles), the default scene's nodes and its mesh nodes (with and without a
skin), node transforms (TRS or matrix), the bones of the skins used, the skeleton order (joints
and their ancestors, parents first), unique joint names, and the ``Skeleton`` built from them.
"""
from __future__ import annotations

import heapq

import numpy as np

from ..algebra.transforms import matrix_to_trs, trs_matrix
from ..animation.skeleton import Skeleton
from ._gltf_constants import (AFFINE_TOLERANCE, COMPONENT_NAMES, EXTRAS_KEY, INVERSE_BIND_RESIDUALS, JOINT_OF,
                              QUAT_UNIT_TOLERANCE)
from ._gltf_document import _GltfFile
from ._residuals import with_residuals


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
    m = trs_matrix(t, q, s)
    if not np.isfinite(m).all():
        raise f.error(f"node {i} transform overflows (translation {t}, scale {s})")
    return t, q, s, m


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
            ibm = f.accessor(skin.inverseBindMatrices, f"skin {s} inverseBindMatrices")
            # written by save_gltf: the float64 matrices exactly (residuals in the skin's extras)
            ibm = with_residuals(f, skin, INVERSE_BIND_RESIDUALS, ibm, f"skin {s}")[:len(joints)]
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
            # keyed by the file's joint node: a joint save_gltf added for a further bone of a
            # node stays that bone even where its matrix equals the first bone's
            key = (node, np.asarray(matrix, dtype=np.float64).tobytes())
            if key not in keys:
                keys[key] = len(bone_nodes)
                bone_nodes.append(_joint_node(f, node))
                inverse_bind.append(np.array(matrix, dtype=np.float64))
            slot_map[k] = keys[key]
        maps[s] = slot_map
    return bone_nodes, np.array(inverse_bind).reshape(-1, 4, 4), maps


def _joint_node(f: _GltfFile, j: int) -> int:
    """The node whose motion joint ``j`` has: ``j`` itself, or the node it duplicates when it is a
    joint ``save_gltf`` added for a further bone of a shared node (``JOINT_OF``: a child of that
    node without transform, children, mesh or skin; anything else is an ordinary node)."""
    node = f.items("nodes")[j]
    ours = node.extras.get(EXTRAS_KEY) if isinstance(node.extras, dict) else None
    of = ours.get(JOINT_OF) if isinstance(ours, dict) else None
    nodes = f.items("nodes")
    if isinstance(of, bool) or not isinstance(of, int) or not 0 <= of < len(nodes):
        return j
    plain = (node.children in (None, []) and node.mesh is None and node.skin is None
             and node.camera is None and node.translation is None and node.rotation is None
             and node.scale is None and node.matrix is None)
    return of if plain and j in (nodes[of].children or []) else j


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


def _build_skeleton(f: _GltfFile, bone_file_nodes: list[int], inverse_bind: np.ndarray,
                    parents: list[int]):
    """The ``Skeleton`` of the merged skins and the map file node -> skeleton node.

    bone_file_nodes : file node of each bone; inverse_bind : (b, 4, 4) float64;
    parents : parent file node of every file node (-1 for roots)
    returns : (Skeleton, {file node: skeleton node})
    """
    nodes = f.items("nodes")
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
    return skeleton, node_to_skeleton


def _mesh_nodes(f: _GltfFile, scene_nodes: list[int]):
    """The mesh nodes of the scene: ([(node, skin)] with a skin, [node] without), in scene order."""
    nodes = f.items("nodes")
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
    return skinned, rigid
