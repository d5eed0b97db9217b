"""Random glTF documents, skinned by cgaskin and by the independent reference (gltf_reference.py).

Hypothesis draws what real files vary in and the shared models do not show all of: node trees in any
index order (parents after their children), non-joint ancestors (animated too), joints listed in any
order, the skinned mesh node anywhere in the tree with a transform of its own (which the
specification says to ignore), matrix nodes (sheared or mirrored ones too), non-uniform and negative
scales, inverse bind matrices that are not the inverse of the rest pose, every interpolation on every
path, keys that do not start at 0, and times before, between, on and after the keys.
"""
import warnings

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import cgaskin

from tests.helpers.gltf_reference import reference_skin
from tests.helpers.gltf_files import Gltf

FINITE = dict(allow_nan=False, allow_infinity=False)


def unit_quaternion(draw):
    q = np.array(draw(st.tuples(*[st.floats(-1, 1, **FINITE)] * 4)))
    return q / np.linalg.norm(q) if np.linalg.norm(q) > 0.1 else np.array([0.0, 0.0, 0.0, 1.0])


def scale3(draw):
    """Uniform or not, sometimes mirrored, bounded away from 0 (a singular joint has no inverse)."""
    s = np.array(draw(st.tuples(*[st.floats(0.4, 2.5)] * 3)))
    if draw(st.booleans()):
        s[:] = s[0]
    if draw(st.integers(0, 4)) == 0:
        s[draw(st.integers(0, 2))] *= -1
    return s


def node_transform(draw):
    """A node's JSON transform: none, some of T/R/S, or a matrix (rigid, scaled or sheared)."""
    kind = draw(st.sampled_from(["none", "trs", "trs", "trs", "matrix"]))
    node = {}
    if kind == "trs":
        if draw(st.booleans()):
            node["translation"] = list(draw(st.tuples(*[st.floats(-2, 2)] * 3)))
        if draw(st.booleans()):
            node["rotation"] = unit_quaternion(draw).tolist()
        if draw(st.booleans()):
            node["scale"] = scale3(draw).tolist()
    elif kind == "matrix":
        m = np.eye(4)
        m[:3, :3] = np.array(draw(st.tuples(*[st.floats(-1.5, 1.5)] * 9))).reshape(3, 3)
        if abs(np.linalg.det(m[:3, :3])) < 0.1:
            m[:3, :3] += np.eye(3)
        m[:3, 3] = draw(st.tuples(*[st.floats(-2, 2)] * 3))
        node["matrix"] = m.T.reshape(-1).tolist()   # column-major
    return node


def key_values(draw, path, count, cubic):
    rows = 3 * count if cubic else count
    if path == "rotation":
        return np.array([unit_quaternion(draw) for _ in range(rows)])
    if path == "scale":
        return np.array([scale3(draw) for _ in range(rows)])
    return np.array(draw(st.lists(st.tuples(*[st.floats(-2, 2)] * 3), min_size=rows, max_size=rows)))


@st.composite
def documents(draw):
    """(Gltf, the key times of each clip): a random skinned document."""
    n_nodes = draw(st.integers(2, 7))
    # node k's parent is an earlier node in tree order; file indices are a random permutation of it
    parents = [-1] + [draw(st.integers(-1, k - 1)) for k in range(1, n_nodes)]
    order = draw(st.permutations(range(n_nodes)))          # tree position -> file index
    nodes = [None] * n_nodes
    for k in range(n_nodes):
        nodes[order[k]] = {"name": f"n{k}", **node_transform(draw)}
    for k, p in enumerate(parents):
        if p >= 0:
            nodes[order[p]].setdefault("children", []).append(order[k])
    roots = [order[k] for k in range(n_nodes) if parents[k] < 0]
    joints = draw(st.lists(st.integers(0, n_nodes - 1), min_size=1, max_size=n_nodes, unique=True))

    g = Gltf()
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    n_vertices = draw(st.integers(3, 24))
    positions = rng.uniform(-1, 1, (n_vertices, 3))
    triangles = np.array([rng.choice(n_vertices, 3, replace=False) for _ in range(n_vertices)])
    influence = rng.integers(0, len(joints), (n_vertices, 4))
    weights = rng.uniform(0, 1, (n_vertices, 4)) * (rng.uniform(0, 1, (n_vertices, 4)) < 0.7)
    weights[:, 0] += 0.05
    weights /= weights.sum(axis=1, keepdims=True)
    skin = {"joints": joints}
    if draw(st.booleans()):
        ibm = np.array([np.linalg.inv(np.array(node_matrix(nodes, j))) for j in joints])
        if draw(st.booleans()):   # bind matrices that are not the rest pose's
            ibm = ibm @ np.linalg.inv(np.array(node_matrix([node_transform(draw)], 0)))
        skin["inverseBindMatrices"] = g.accessor(ibm.transpose(0, 2, 1).reshape(-1, 16), 5126, "MAT4")
    mesh_node = {"name": "mesh", "mesh": 0, "skin": 0, **node_transform(draw)}
    host = draw(st.integers(-1, n_nodes - 1))
    nodes.append(mesh_node)
    if host < 0:
        roots.append(n_nodes)
    else:
        nodes[host].setdefault("children", []).append(n_nodes)
    g.doc.update(
        scene=0, scenes=[{"nodes": roots}], nodes=nodes, skins=[skin],
        meshes=[{"primitives": [{"attributes": {
            "POSITION": g.accessor(positions, 5126, "VEC3", min=positions.min(0).astype(np.float32).tolist(),
                                   max=positions.max(0).astype(np.float32).tolist()),
            "JOINTS_0": g.accessor(influence, 5121, "VEC4"),
            "WEIGHTS_0": g.accessor(weights, 5126, "VEC4")},
            "indices": g.accessor(triangles.reshape(-1), 5125, "SCALAR")}]}])

    # clips: channels on TRS nodes (the spec forbids animating a matrix node), any node of the tree
    animatable = [i for i in range(n_nodes) if "matrix" not in nodes[i]]
    animations = []
    for _ in range(draw(st.integers(0, 2)) if animatable else 0):
        samplers, channels, used = [], [], set()
        for _ in range(draw(st.integers(1, 4))):
            node = draw(st.sampled_from(animatable))
            path = draw(st.sampled_from(["translation", "rotation", "scale"]))
            if (node, path) in used:
                continue
            used.add((node, path))
            interpolation = draw(st.sampled_from(["LINEAR", "STEP", "CUBICSPLINE"]))
            count = draw(st.integers(1, 4))
            times = np.cumsum(rng.uniform(0.1, 1.0, count)) + draw(st.floats(-0.5, 1.0))
            values = key_values(draw, path, count, interpolation == "CUBICSPLINE")
            samplers.append({"input": g.accessor(times, 5126, "SCALAR", min=[float(np.float32(times[0]))],
                                                 max=[float(np.float32(times[-1]))]),
                             "output": g.accessor(values, 5126, "VEC4" if path == "rotation" else "VEC3"),
                             "interpolation": interpolation})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})
        animations.append({"samplers": samplers, "channels": channels})
    if animations:
        g.doc["animations"] = animations
    return g, [np.concatenate([g_times(g, s["input"]) for s in a["samplers"]]) for a in animations]


def g_times(g, accessor):
    """The float32 key times an accessor of ``g`` holds."""
    acc = g.doc["accessors"][accessor]
    view = g.doc["bufferViews"][acc["bufferView"]]
    return np.frombuffer(bytes(g.blob), "<f4", acc["count"], view["byteOffset"] + acc["byteOffset"])


def node_matrix(nodes, index):
    """Rest global matrix of node ``index`` (for bind matrices), composed up the tree."""
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    m = np.eye(4)
    while index is not None:
        m = local_matrix(nodes[index]) @ m
        index = parent.get(index)
    return m


def local_matrix(node):
    if "matrix" in node:
        return np.array(node["matrix"]).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def diagonal(points):
    return float(np.linalg.norm(np.ptp(points, axis=0)))


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow], deadline=None)
@given(doc=documents(), fractions=st.lists(st.floats(-0.3, 1.3), min_size=1, max_size=4),
       container=st.sampled_from(["q.glb", "q.gltf"]))
def test_random_documents_skin_like_the_reference(tmp_path_factory, doc, fractions, container):
    g, clip_keys = doc
    path = g.write(tmp_path_factory.mktemp("doc") / container)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")       # float32 weights that do not sum to 1 exactly
        rig = cgaskin.load(path)
    expected = reference_skin(path, None, 0.0, max_influences=4)
    scale = max(diagonal(expected), 1e-3)
    np.testing.assert_allclose(cgaskin.skin(rig), expected, rtol=0, atol=1e-9 * scale)
    for index, keys in enumerate(clip_keys):
        start = float(keys.min())
        times = [start + f * (float(keys.max()) - start) for f in fractions] + keys[:3].tolist()
        for t in times:
            expected = reference_skin(path, index, t, max_influences=4)
            got = cgaskin.skin(rig, rig.pose(index, t))
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * max(diagonal(expected), 1e-3),
                                       err_msg=f"clip {index} at t={t}")
