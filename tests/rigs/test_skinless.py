"""Models without a skin (issue 10, "any model a user has"): mesh nodes without ``skin`` load as rigid
bones (the static formats assimp reads: tests/rigs/test_static_formats.py).

Oracle: plain 4x4 matrices built here from the file's TRS/matrix values (world = product of the
parent chain, root first); positions are those matrices applied to the stored vertices.
"""
import json
import struct

import numpy as np
import pytest

import cgaskin
from cgaskin.errors import NoSkinError
from cgaskin.rigs.gltf import load_gltf

from tests.helpers.cut_checks import check_cut, volume
from tests.helpers.gltf_files import QUAD_VERTICES, Gltf, assert_valid_rig, load_quietly
from tests.helpers.tear_checks import check_like_original, check_stroke, some_tear


# --- the oracle --------------------------------------------------------------------------------------

def quat_matrix(q):
    q = np.asarray(q, float)
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"], float).reshape(4, 4).T      # column-major in the file
    m = np.eye(4)
    m[:3, :3] = quat_matrix(node.get("rotation", [0, 0, 0, 1])) @ np.diag(node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def world_matrices(nodes, override=None):
    """Global matrix of every node (``override``: {node: replacement node dict})."""
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    out = {}

    def world(i):
        if i not in out:
            local = local_matrix((override or {}).get(i, nodes[i]))
            out[i] = local if i not in parent else world(parent[i]) @ local
        return out[i]
    for i in range(len(nodes)):
        world(i)
    return out


def apply(m, points):
    return points @ m[:3, :3].T + m[:3, 3]


def unit(q):
    return list(np.asarray(q, float) / np.linalg.norm(q))


# --- test files -------------------------------------------------------------------------------------

def box(g, subdivisions=0):
    """A closed, outward (counter-clockwise) unit box centred at 0 with normals; its mesh dict."""
    import trimesh
    mesh = trimesh.creation.box()
    for _ in range(subdivisions):
        mesh = mesh.subdivide()
    v = np.asarray(mesh.vertices, float)
    assert volume(v, np.asarray(mesh.faces)) > 0
    normals = v / np.linalg.norm(v, axis=1, keepdims=True)
    return {"primitives": [{"attributes": {"POSITION": g.accessor(v, 5126, "VEC3"),
                                           "NORMAL": g.accessor(normals, 5126, "VEC3")},
                            "indices": g.accessor(np.asarray(mesh.faces).reshape(-1), 5125, "SCALAR")}]}, v


QUAD_STRIP = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)


def nested_scene():
    """Nested nodes with TRS and matrix transforms, one mesh used twice (once mirrored), a strip
    mesh at the root, and a clip that moves the root (the parent of two mesh nodes)."""
    g = Gltf()
    box_mesh, box_v = box(g)
    strip = {"primitives": [{"mode": 5, "attributes": {
        "POSITION": g.accessor(QUAD_STRIP, 5126, "VEC3"),
        "NORMAL": g.accessor(np.tile([0, 0, 1.0], (4, 1)), 5126, "VEC3")}}]}
    arm = np.eye(4)
    arm[:3, :3] = quat_matrix([0.3, -0.2, 0.4, 0.8]) @ np.diag([1.0, 1.5, 0.5])
    arm[:3, 3] = [0.5, -1.0, 2.0]
    nodes = [
        {"name": "Root", "translation": [1, 2, 3], "rotation": unit([0.1, 0.7, -0.2, 0.6]),
         "scale": [2, 2, 2], "children": [1, 3]},
        {"name": "Arm", "matrix": arm.T.reshape(-1).tolist(), "children": [2]},
        {"name": "Box", "mesh": 0, "translation": [0, 0.5, 0], "rotation": unit([0, 0, 0.38, 0.92])},
        {"name": "Mirror", "mesh": 0, "translation": [3, 0, 0], "scale": [-1, 1.2, 1]},
        {"name": "Plain", "mesh": 1},
    ]
    times = np.array([0.0, 1.0, 2.0])
    translations = np.array([[1, 2, 3], [2, 2, 3], [2, 4, 1]], float)
    rotations = np.array([unit([0.1, 0.7, -0.2, 0.6]), unit([0, 0, 0.6, 0.8]), unit([0.5, 0.5, 0.5, 0.5])])
    t_in = g.accessor(times, 5126, "SCALAR", min=[0.0], max=[2.0])
    g.doc.update(scene=0, scenes=[{"nodes": [0, 4]}], nodes=nodes, meshes=[box_mesh, strip],
                 animations=[{"name": "move", "samplers": [
                     {"input": t_in, "output": g.accessor(translations, 5126, "VEC3")},
                     {"input": t_in, "output": g.accessor(rotations, 5126, "VEC4")}],
                     "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}},
                                  {"sampler": 1, "target": {"node": 0, "path": "rotation"}}]}])
    # float32 in the file: the oracle reads what is stored
    keys = [dict(nodes[0], translation=t.astype(np.float32).tolist(), rotation=r.astype(np.float32).tolist())
            for t, r in zip(translations, rotations)]
    return g, box_v.astype(np.float32).astype(float), keys, times


def expected_positions(nodes, box_v, override=None):
    w = world_matrices(nodes, override)
    return [apply(w[2], box_v), apply(w[3], box_v), apply(w[4], QUAD_STRIP)], w


def test_nested_rigid_meshes_rest_and_clip(tmp_path):
    g, box_v, keys, times = nested_scene()
    rig = load_gltf(g.write(tmp_path / "nested.glb"))
    assert_valid_rig(rig)
    nodes = g.doc["nodes"]
    rest, w = expected_positions(nodes, box_v)
    n_box = len(box_v)
    assert rig.n_vertices == 2 * n_box + 4
    diag = np.linalg.norm(np.ptp(np.concatenate(rest), axis=0))
    # rig.vertices: the rest world positions, in scene order (Box, Mirror, Plain)
    np.testing.assert_allclose(rig.vertices, np.concatenate(rest), rtol=0, atol=1e-12 * diag)
    np.testing.assert_allclose(cgaskin.skin(rig, rig.rest_pose()), np.concatenate(rest), rtol=0, atol=1e-12 * diag)
    # each mesh node a bone with weight 1; the skeleton: the mesh nodes and their ancestors
    sk = rig.skeleton
    assert sorted(sk.names) == ["Arm", "Box", "Mirror", "Plain", "Root"]
    assert [sk.names[b] for b in sk.bone_nodes] == ["Box", "Mirror", "Plain"]
    assert rig.joints[:, 0].tolist() == [0] * n_box + [1] * n_box + [2] * 4
    assert (rig.weights[:, 0] == 1).all() and (rig.weights[:, 1:] == 0).all()
    for b, node in enumerate((2, 3, 4)):
        np.testing.assert_allclose(sk.inverse_bind[b] @ w[node], np.eye(4), atol=1e-12)
    # the clip moves the root, so all three meshes, and the two under it follow
    assert rig.clips[0].name == "move"
    for key, t in zip(keys, times):
        posed, _ = expected_positions(nodes, box_v, {0: key})
        np.testing.assert_allclose(cgaskin.skin(rig, rig.pose("move", t)), np.concatenate(posed),
                                   rtol=0, atol=1e-12 * diag)
    # a pose edit on the matrix node moves the box below it only
    bent = cgaskin.skin(rig, rig.rest_pose().rotate("Arm", [0, 0, 1], 0.5))
    assert not np.allclose(bent[:n_box], rest[0])
    np.testing.assert_array_equal(bent[n_box:], cgaskin.skin(rig, rig.rest_pose())[n_box:])


def test_mirrored_node_keeps_faces_outward_and_normals_transformed(tmp_path):
    g, box_v, _, _ = nested_scene()
    rig = load_gltf(g.write(tmp_path / "nested.glb"))
    nodes = g.doc["nodes"]
    w = world_matrices(nodes)
    assert np.linalg.det(w[3][:3, :3]) < 0 < np.linalg.det(w[2][:3, :3])
    n_box = len(box_v)
    for k, node in enumerate((2, 3)):
        part = slice(k * n_box, (k + 1) * n_box)
        faces = rig.faces[(rig.faces >= k * n_box).all(axis=1) & (rig.faces < (k + 1) * n_box).all(axis=1)]
        # a closed box: outward (counter-clockwise) faces enclose a positive volume
        assert volume(rig.vertices, faces) > 0, node
        np.testing.assert_allclose(volume(rig.vertices, faces), abs(np.linalg.det(w[node][:3, :3])), rtol=1e-6)
        # normals: inverse transpose, normalised, still pointing out of the box
        n_local = box_v / np.linalg.norm(box_v, axis=1, keepdims=True)
        expected = n_local @ np.linalg.inv(w[node][:3, :3])
        expected /= np.linalg.norm(expected, axis=1, keepdims=True)
        np.testing.assert_allclose(rig.attributes["NORMAL"][part], expected, atol=1e-6)
        centre = apply(w[node], np.zeros((1, 3)))
        assert (np.einsum("ij,ij->i", rig.attributes["NORMAL"][part], rig.vertices[part] - centre) > 0).all()
    # the strip (mode 5) under an identity transform: its winding as the spec derives it
    strip = rig.faces[(rig.faces >= 2 * n_box).all(axis=1)] - 2 * n_box
    assert strip.tolist() == [[0, 1, 2], [1, 3, 2]]


def test_skinless_quad_and_its_save_round_trip(tmp_path):
    g = Gltf.quad()
    del g.doc["nodes"][3]["skin"]
    g.doc["nodes"][3]["translation"] = [0, 0, -2]
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert_valid_rig(rig)
    assert rig.skeleton.names == ["quad"] and rig.joints[:, 0].tolist() == [0] * 4
    expected = np.array([[0, 0, -2], [0.5, 0, -2], [0.5, 0.5, -2], [0, 0.5, -2]])
    np.testing.assert_array_equal(rig.vertices, expected)
    # saved as a skinned glTF 2.0 file, it reloads and skins to the same place
    back = load_gltf(cgaskin.save(rig, tmp_path / "saved.glb"))
    np.testing.assert_allclose(cgaskin.skin(back, back.rest_pose()), expected, atol=1e-6)
    assert back.skeleton.names == ["quad"]


def test_mixed_file_loads_rigid_props_at_the_skins_bind_pose(tmp_path):
    """A rigid prop hanging from joint B of a skinned quad: it comes along, lies where the skin's
    bind pose puts B (here the identity, not B's rest transform), and follows B when posed."""
    g = Gltf.quad()
    prop = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], np.float32).astype(float)
    g.doc["meshes"].append({"primitives": [{"attributes": {"POSITION": g.accessor(prop, 5126, "VEC3")}}]})
    g.doc["nodes"].append({"name": "prop", "mesh": 1, "translation": [0, 0.2, 0]})
    g.doc["nodes"][2]["children"] = [4]
    rig = load_gltf(g.write(tmp_path / "q.glb"))
    assert_valid_rig(rig)
    assert rig.n_vertices == 7 and rig.skeleton.names == ["Armature", "A", "B", "prop"]
    np.testing.assert_array_equal(rig.vertices[4:], prop + [0, 0.2, 0])      # B's bind global: identity
    assert rig.joints[4:, 0].tolist() == [2] * 3 and rig.skeleton.bone_nodes.tolist() == [1, 2, 3]
    w = world_matrices(g.doc["nodes"])
    np.testing.assert_allclose(cgaskin.skin(rig, rig.rest_pose())[4:], apply(w[4], prop), atol=1e-15)
    bent = rig.rest_pose().rotate("B", [0, 0, 1], np.pi / 2)
    turned = dict(g.doc["nodes"][2], rotation=[0, 0, np.sin(np.pi / 4), np.cos(np.pi / 4)])
    np.testing.assert_allclose(cgaskin.skin(rig, bent)[4:], apply(world_matrices(g.doc["nodes"], {2: turned})[4], prop),
                               atol=1e-12)


def test_cut_and_tear_a_skinless_box(tmp_path):
    g = Gltf()
    mesh, _ = box(g, subdivisions=3)
    g.doc.update(scene=0, scenes=[{"nodes": [0]}], meshes=[mesh],
                 nodes=[{"name": "scan", "mesh": 0, "rotation": unit([0.2, 0.1, 0.3, 0.9]), "scale": [2, 1, 1]}])
    rig = load_gltf(g.write(tmp_path / "box.glb"))
    normal, point = [0.3, 1.0, 0.2], [0.05, 0.1, 0.0]
    check_cut(rig, cgaskin.cut_details(rig, normal, point, cap=True), closed=True, capped=True)
    result = cgaskin.cut_details(rig, normal, point)
    a, b = cgaskin.cut(rig, normal, point)
    d = rig.vertices @ result.plane[:3] - result.plane[3]
    on = int((np.abs(d) <= result.tolerance).sum())
    k = len(result.edge_vertices)
    # each input vertex goes to its side (both when on the plane), each crossing to both halves
    assert k > 0 and a.n_vertices + b.n_vertices == rig.n_vertices + on + 2 * k
    assert a.n_vertices == (d > result.tolerance).sum() + on + k
    # a tear stroke on the skinless box; the torn box skins, poses and exports like the original
    torn = some_tear(rig, seed=1)
    check_stroke(rig, torn, None)
    check_like_original(rig, torn.rig, rig.rest_pose().rotate("scan", [0, 1, 0], 0.4), tmp_path)


def test_tear_a_skinless_plane(tmp_path):
    """cgaskin.tear on a subdivided square under a moved, turned node (it stays in z = 1)."""
    n = 9
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    grid = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    faces = np.concatenate([np.stack([i, i + 1, i + n + 1], 1), np.stack([i, i + n + 1, i + n], 1)])
    g = Gltf()
    g.doc.update(scene=0, scenes=[{"nodes": [0]}], nodes=[
        {"name": "sheet", "mesh": 0, "translation": [2, 0, 1], "rotation": [0, 0, np.sin(0.3), np.cos(0.3)]}],
        meshes=[{"primitives": [{"attributes": {"POSITION": g.accessor(grid, 5126, "VEC3")},
                                 "indices": g.accessor(faces.ravel(), 5125, "SCALAR")}]}])
    rig = load_gltf(g.write(tmp_path / "sheet.glb"))
    np.testing.assert_allclose(rig.vertices[:, 2], 1.0, atol=1e-15)
    centre = rig.vertices.mean(axis=0)
    step = np.array([0.3, 0.05, 0.0])
    blade = [np.array([c + [0, 0, 1], c - [0, 0, 1]]) for c in (centre - step, centre + step)]
    torn = cgaskin.tear(rig, blade[0], blade[1], opening=0.02)
    assert_valid_rig(torn)
    assert torn.n_vertices > rig.n_vertices and torn.n_faces > rig.n_faces
    assert np.isfinite(cgaskin.skin(torn, torn.rest_pose().translate("sheet", [0, 0, 1]))).all()


# --- a real model with its skin stripped -------------------------------------------------------------

def glb_parts(data: bytes):
    length = struct.unpack_from("<I", data, 12)[0]
    return json.loads(data[20:20 + length]), data[20 + length + 8:]


def glb_bytes(doc, blob):
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def test_fox_without_its_skin(models_dir, tmp_path):
    fox = models_dir / "Fox.glb"
    if not fox.exists():
        pytest.skip(f"{fox} missing")
    doc, blob = glb_parts(fox.read_bytes())
    mesh_node = next(i for i, n in enumerate(doc["nodes"]) if "mesh" in n)
    for node in doc["nodes"]:
        node.pop("skin", None)
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            for name in ("JOINTS_0", "WEIGHTS_0"):
                prim["attributes"].pop(name, None)
    doc["nodes"][mesh_node].update(translation=[10, -5, 3], rotation=unit([0.3, 0, 0.4, 0.8]), scale=[1.5, 1.5, 1.5])
    path = tmp_path / "fox_static.glb"
    path.write_bytes(glb_bytes(doc, blob))
    rig = load_quietly(path)
    assert_valid_rig(rig)
    positions = load_quietly(fox).vertices                  # the stored POSITION, as the skinned load reads it
    expected = apply(world_matrices(doc["nodes"])[mesh_node], positions)
    diag = np.linalg.norm(np.ptp(expected, axis=0))
    np.testing.assert_allclose(rig.vertices, expected, rtol=0, atol=1e-12 * diag)
    np.testing.assert_allclose(cgaskin.skin(rig, rig.rest_pose()), expected, rtol=0, atol=1e-12 * diag)
    assert rig.skeleton.n_bones == 1 and "TEXCOORD_0" in rig.attributes
    # the joints' animations have nothing to move: the clips are kept, empty
    assert [c.name for c in rig.clips] == ["Survey", "Walk", "Run"]


# --- several skinned meshes, no mesh, nothing visible ----------------------------------------------------

def test_two_skinned_meshes_load_as_one_rig(models_dir, tmp_path):
    src = models_dir / "simple_skin.gltf"
    if not src.exists():
        pytest.skip(f"{src} missing")
    doc = json.loads(src.read_text())
    doc["nodes"].append({"mesh": 0, "skin": 1, "name": "copy"})
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    doc["skins"].append(dict(doc["skins"][0]))
    path = tmp_path / "two.gltf"
    path.write_text(json.dumps(doc))
    one, two = load_gltf(src), load_gltf(path)
    assert two.n_vertices == 2 * one.n_vertices and two.n_faces == 2 * one.n_faces
    np.testing.assert_array_equal(two.vertices, np.concatenate([one.vertices] * 2))
    pose = two.pose(0, 1.0)
    np.testing.assert_array_equal(cgaskin.skin(two, pose), np.concatenate([cgaskin.skin(one, one.pose(0, 1.0))] * 2))


def test_no_mesh_no_triangles_and_meshes_scaled_to_zero(tmp_path):
    g = Gltf.quad()
    del g.doc["nodes"][3]["mesh"], g.doc["nodes"][3]["skin"]
    with pytest.raises(NoSkinError, match=r"q.glb: holds no mesh \(no node of its scene has one\)"):
        load_gltf(g.write(tmp_path / "q.glb"))
    g = Gltf.quad()
    del g.doc["nodes"][3]["skin"]
    g.primitive["mode"] = 0                                       # points
    with pytest.warns(UserWarning, match="not triangles"):
        with pytest.raises(NoSkinError, match=r"holds no triangle mesh"):
            load_gltf(g.write(tmp_path / "q.glb"))
    # a mesh scaled to 0 at rest (a prop a clip makes appear): local vertices, identity inverse bind
    g = Gltf.quad()
    del g.doc["nodes"][3]["skin"]
    g.doc["nodes"][3].update(scale=[1, 0, 1], translation=[0, 0, 3])
    t_in = g.accessor([0.0, 1.0], 5126, "SCALAR", min=[0.0], max=[1.0])
    g.doc["animations"] = [{"samplers": [{"input": t_in, "output": g.accessor([[1, 0, 1], [1, 2, 1]], 5126, "VEC3")}],
                            "channels": [{"sampler": 0, "target": {"node": 3, "path": "scale"}}]}]
    with pytest.warns(UserWarning, match=r"node 3 \('quad'\) has a singular transform \(a scale of 0\)"):
        rig = load_gltf(g.write(tmp_path / "q.glb"))
    np.testing.assert_array_equal(rig.vertices, QUAD_VERTICES)
    np.testing.assert_array_equal(rig.skeleton.inverse_bind, [np.eye(4)])
    np.testing.assert_allclose(cgaskin.skin(rig, rig.rest_pose()), QUAD_VERTICES * [1, 0, 1] + [0, 0, 3])
    np.testing.assert_allclose(cgaskin.skin(rig, rig.pose(0, 1.0)), QUAD_VERTICES * [1, 2, 1] + [0, 0, 3])
