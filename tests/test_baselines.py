"""The numpy reference skinning (cgaskin.baselines) and the independent glTF oracle (gltf_reference)."""
import numpy as np
import pytest

from cgaskin import baselines as B
from cgaskin.errors import InvalidInputError

from tests.helpers import gltf_reference as R


def _axis_angle(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.append(np.sin(angle / 2) * axis, np.cos(angle / 2))


def _same_rotation(q1, q2, atol=1e-12):
    """q and -q are the same rotation."""
    return min(np.abs(q1 - q2).max(), np.abs(q1 + q2).max()) <= atol


# --------------------------------------------------------------------------------------------------
# Quaternions and matrices


def test_quat_matrix_round_trip_random():
    rng = np.random.default_rng(0)
    q = rng.normal(size=(500, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    m = B.quat_to_matrix(q)
    assert np.allclose(m @ m.transpose(0, 2, 1), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(m), 1.0, atol=1e-14)
    back = B.matrix_to_quat(m)
    assert np.all(back[:, 3] >= 0)
    for a, b in zip(q, back):
        assert _same_rotation(a, b, 1e-14)
    assert np.allclose(B.quat_to_matrix(back), m, atol=1e-14)


@pytest.mark.parametrize("axis", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, -2, 3), (0, 1, -1e-9)])
@pytest.mark.parametrize("degrees", [180.0, 179.999995, 180.000005, 0.0, 1e-7, 90.0])
def test_quat_round_trip_near_180(axis, degrees):
    q = _axis_angle(axis, np.radians(degrees))
    m = B.quat_to_matrix(q)
    back = B.matrix_to_quat(m)
    assert abs(np.linalg.norm(back) - 1) < 1e-15
    assert _same_rotation(q, back, 1e-12)
    # 4x4 input reads the upper-left block
    m4 = np.eye(4)
    m4[:3, :3] = m
    m4[:3, 3] = (5, 6, 7)
    assert _same_rotation(q, B.matrix_to_quat(m4), 1e-12)


def test_matrix_to_quat_exact_half_turns():
    for m in (np.diag([1.0, -1, -1]), np.diag([-1.0, 1, -1]), np.diag([-1.0, -1, 1])):
        q = B.matrix_to_quat(m)
        assert np.allclose(B.quat_to_matrix(q), m, atol=1e-15)
        assert abs(q[3]) < 1e-15


def test_trs_matrix_order_and_broadcast():
    t = np.array([1.0, -2.0, 3.0])
    q = _axis_angle((0, 0, 1), np.pi / 2)
    s = np.array([2.0, 3.0, 4.0])
    m = B.trs_matrix(t, q, s)
    # T @ R @ S: scale first, then rotate, then translate
    p = np.array([1.0, 1.0, 1.0])
    expected = np.array([-3.0, 2.0, 4.0]) + t   # S p = (2,3,4); Rz90 (x,y,z) = (-y,x,z)
    assert np.allclose(m[:3, :3] @ p + m[:3, 3], expected, atol=1e-14)
    assert np.allclose(m[3], [0, 0, 0, 1])
    batch = B.trs_matrix(np.zeros((5, 3)), q, np.ones(3))
    assert batch.shape == (5, 4, 4)


def test_global_matrices_chain_and_order():
    local = np.array([B.trs_matrix([1.0, 0, 0], _axis_angle((0, 0, 1), np.pi / 2), np.ones(3))] * 3)
    g = B.global_matrices([-1, 0, 1], local)
    assert np.allclose(g[2], local[0] @ local[1] @ local[2])
    # joint 2 sits at (1,0,0) + Rz90 (1,0,0) + Rz180 (1,0,0) = (0, 1, 0)
    assert np.allclose(g[2][:3, 3], [0.0, 1.0, 0.0], atol=1e-15)
    with pytest.raises(InvalidInputError):
        B.global_matrices([1, -1], local[:2])


# --------------------------------------------------------------------------------------------------
# Skinning


def _random_bones(rng, n, scale=None):
    q = rng.normal(size=(n, 4))
    s = np.ones((n, 3)) if scale is None else scale
    return B.trs_matrix(rng.normal(size=(n, 3)) * 3, q / np.linalg.norm(q, axis=1, keepdims=True), s)


def test_lbs_single_influence_is_matrix_product():
    rng = np.random.default_rng(1)
    bones = _random_bones(rng, 5)
    v = rng.normal(size=(50, 3))
    j = rng.integers(0, 5, size=(50, 1))
    out = B.lbs_matrices(v, j, np.ones((50, 1)), bones)
    expected = np.einsum("nij,nj->ni", bones[j[:, 0], :3, :3], v) + bones[j[:, 0], :3, 3]
    assert np.allclose(out, expected, atol=1e-13)


@pytest.mark.parametrize("scale", ["rigid", "uniform", "non-uniform"])
def test_dqs_equals_lbs_for_one_influence(scale):
    rng = np.random.default_rng(2)
    s = {"rigid": np.ones((6, 3)), "uniform": np.repeat(rng.uniform(0.1, 10, (6, 1)), 3, axis=1),
         "non-uniform": rng.uniform(0.5, 2, (6, 3))}[scale]
    bones = _random_bones(rng, 6, s)
    v = rng.normal(size=(100, 3)) * 4
    # one real influence, the other slots carry weight 0 on random bones
    j = rng.integers(0, 6, size=(100, 4))
    w = np.zeros((100, 4))
    w[:, 0] = 1.0
    assert np.allclose(B.dqs(v, j, w, bones), B.lbs_matrices(v, j, w, bones), atol=1e-12)


def test_dqs_equals_lbs_for_translations_only():
    rng = np.random.default_rng(3)
    bones = B.trs_matrix(rng.normal(size=(4, 3)), np.array([0, 0, 0, 1.0]), np.ones(3))
    v = rng.normal(size=(30, 3))
    j = rng.integers(0, 4, size=(30, 4))
    w = rng.dirichlet(np.ones(4), size=30)
    assert np.allclose(B.dqs(v, j, w, bones), B.lbs_matrices(v, j, w, bones), atol=1e-13)


def test_dqs_preserves_radius_where_lbs_collapses():
    """The candy-wrapper: a cylinder about x, half-way between a still bone and one twisted 180°."""
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    v = np.stack([np.full(16, 0.5), np.cos(angles), np.sin(angles)], axis=1)
    bones = np.array([np.eye(4), B.trs_matrix(np.zeros(3), _axis_angle((1, 0, 0), np.pi), np.ones(3))])
    j = np.tile([0, 1], (16, 1))
    w = np.full((16, 2), 0.5)
    lbs = B.lbs_matrices(v, j, w, bones)
    dq = B.dqs(v, j, w, bones)
    assert np.allclose(np.linalg.norm(lbs[:, 1:], axis=1), 0.0, atol=1e-15)   # collapsed to the axis
    assert np.allclose(np.linalg.norm(dq[:, 1:], axis=1), 1.0, atol=1e-14)    # radius kept
    assert np.allclose(dq[:, 0], 0.5, atol=1e-15)
    # and for a whole range of twists and blend weights
    for deg in (30, 90, 150, 179):
        bones[1] = B.trs_matrix(np.zeros(3), _axis_angle((1, 0, 0), np.radians(deg)), np.ones(3))
        for a in (0.1, 0.5, 0.9):
            w = np.tile([1 - a, a], (16, 1))
            dq = B.dqs(v, j, w, bones)
            assert np.allclose(np.linalg.norm(dq[:, 1:], axis=1), 1.0, atol=1e-13)


def test_dqs_antipodal_quaternions_blend_the_short_way():
    """q and -q are one rotation: a blend of bone matrices cannot care which sign matrix_to_quat gives."""
    bones = np.array([B.trs_matrix([0, 0, 0], _axis_angle((0, 0, 1), np.radians(170)), np.ones(3)),
                      B.trs_matrix([0, 0, 0], _axis_angle((0, 0, 1), np.radians(-170)), np.ones(3))])
    v = np.array([[1.0, 0.0, 0.0]])
    out = B.dqs(v, [[0, 1]], [[0.5, 0.5]], bones)
    # the short way between +170° and -170° passes through 180°, not 0°
    assert np.allclose(out, [[-1.0, 0.0, 0.0]], atol=1e-14)


def test_dqs_refuses_reflections():
    bones = np.array([np.diag([-1.0, 1, 1, 1])])
    with pytest.raises(InvalidInputError):
        B.dqs(np.zeros((1, 3)), [[0]], [[1.0]], bones)


def test_skin_input_shapes_checked():
    with pytest.raises(InvalidInputError):
        B.lbs_matrices(np.zeros((2, 3)), [[0], [3]], [[1.0], [1.0]], np.eye(4)[None])
    with pytest.raises(InvalidInputError):
        B.lbs_matrices(np.zeros((2, 2)), [[0], [0]], [[1.0], [1.0]], np.eye(4)[None])


# --------------------------------------------------------------------------------------------------
# The independent glTF oracle


def test_reference_simple_skin_rest_pose(models_dir):
    path = models_dir / "simple_skin.gltf"
    bind = R.bind_positions(path)
    assert bind.shape == (10, 3)
    # Both joints rest at y = 1 (node 1 translates by (0, 1, 0), node 2 adds nothing) and both
    # inverse bind matrices translate by (-0.5, -1, 0): every joint matrix is a shift by -0.5 in x.
    assert np.allclose(R.reference_skin(path), bind - [0.5, 0.0, 0.0], atol=1e-15)


def test_reference_simple_skin_animated(models_dir):
    path = models_dir / "simple_skin.gltf"
    bind = R.bind_positions(path)
    # t = 1.0 is a key: node 2 turned 90° about z. Joint 1 matrix: T(0,1,0) Rz90 T(-0.5,-1,0).
    out = R.reference_skin(path, 0, 1.0)
    assert np.allclose(out[8], [-1.0, 0.5, 0.0], atol=1e-6)        # (0, 2, 0), all on joint 1
    assert np.allclose(out[9], [-1.0, 1.5, 0.0], atol=1e-6)        # (1, 2, 0)
    assert np.allclose(out[4], [-0.25, 0.75, 0.0], atol=1e-6)      # (0, 1, 0), half and half
    assert np.allclose(out[0], bind[0] - [0.5, 0, 0], atol=1e-15)  # all on joint 0
    # t = 0.25, half-way between keys 0° and 45°: slerp gives 22.5°
    out = R.reference_skin(path, 0, 0.25)
    a = np.radians(22.5)
    p = np.array([-0.5, 1.0, 0.0])   # (0, 2, 0) after the inverse bind matrix
    expected = np.array([np.cos(a) * p[0] - np.sin(a) * p[1], np.sin(a) * p[0] + np.cos(a) * p[1], 0])
    assert np.allclose(out[8], expected + [0, 1, 0], atol=1e-3)  # keys store 0.383/0.924: 3 digits
    # clamping: before the first key and after the last
    assert np.allclose(R.reference_skin(path, 0, -3.0), R.reference_skin(path, 0, 0.0))
    assert np.allclose(R.reference_skin(path, 0, 99.0), R.reference_skin(path, 0, 5.5))


def test_reference_sampler_semantics():
    times = np.array([0.0, 2.0, 3.0])
    # CUBICSPLINE, one scalar: (in-tangent, value, out-tangent) per key
    values = np.array([[9.0], [0.0], [1.0], [0.0], [1.0], [9.0], [0.0], [1.0], [0.0]])
    # Hermite on [0, 2]: p0 = 0, m0 = 2 s * 1/s, p1 = 1, m1 = 2 s * 0/s; at u = 1/2:
    # h00 = 1/2, h10 = 1/8, h01 = 1/2, h11 = -1/8 -> 0 + 2/8 + 1/2 + 0
    assert R.sample(times, values, "CUBICSPLINE", "translation", 1.0) == pytest.approx([0.75])
    assert R.sample(times, values, "CUBICSPLINE", "translation", 2.0) == pytest.approx([1.0])
    assert R.sample(times, values, "CUBICSPLINE", "translation", 5.0) == pytest.approx([1.0])
    lin = np.array([[0.0], [4.0], [6.0]])
    assert R.sample(times, lin, "LINEAR", "translation", 2.5) == pytest.approx([5.0])
    assert R.sample(times, lin, "STEP", "translation", 2.9) == pytest.approx([4.0])
    assert R.sample(times, lin, "STEP", "translation", -1.0) == pytest.approx([0.0])
    # LINEAR rotation takes the shorter arc: keys +170° and -170° (the latter stored as -q)
    qa = _axis_angle((0, 0, 1), np.radians(170))
    qb = -_axis_angle((0, 0, 1), np.radians(-170))
    q = R.sample(times[:2], np.array([qa, qb]), "LINEAR", "rotation", 1.0)
    assert _same_rotation(q, _axis_angle((0, 0, 1), np.pi), 1e-12)


def test_reference_arm5_rest_pose_is_bind_pose(models_dir):
    """Arm5's nodes rest in the bind pose: skinning the rest pose returns the stored positions
    (up to the float32 rounding of the matrices)."""
    path = models_dir / "Arm5.glb"
    bind = R.bind_positions(path)
    diag = np.linalg.norm(bind.max(0) - bind.min(0))
    assert bind.shape == (2935, 3)
    assert np.abs(R.reference_skin(path) - bind).max() < 1e-6 * diag


def test_reference_agrees_with_lbs_baseline(models_dir):
    """Two separately written blends of the same joint matrices (Fox, mid-animation)."""
    path = models_dir / "Fox.glb"
    f, prims = R.skinned_primitives(path)
    (node, prim), = prims
    skin = f.gltf.skins[f.gltf.nodes[node].skin]
    glob = R.node_globals(f, 1, 0.37)
    bones = glob[skin.joints] @ f.accessor(skin.inverseBindMatrices)
    joints = f.accessor(prim.attributes.JOINTS_0)
    weights = f.accessor(prim.attributes.WEIGHTS_0)
    weights = weights / weights.sum(axis=1, keepdims=True)
    lbs = B.lbs_matrices(f.accessor(prim.attributes.POSITION), joints, weights, bones)
    assert np.allclose(lbs, R.reference_skin(path, 1, 0.37), rtol=0, atol=1e-9)


def test_reference_decoder_strides_normalised_sparse_matrix_nodes(tmp_path):
    """A hand-made file exercising what the real models do not: interleaved attributes (byteStride),
    normalised uint8 weights, a sparse POSITION accessor, a node given by a matrix, a scaled joint,
    a mesh node transform that must be ignored and a missing inverseBindMatrices (identity)."""
    import base64
    import pygltflib as G

    pos = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 0]], np.float32).tobytes()            # 36 bytes
    inter = b"".join(np.array(j, np.uint8).tobytes() + np.array(w, np.uint8).tobytes()
                     for j, w in [([0, 0, 0, 0], [255, 0, 0, 0]), ([1, 0, 0, 0], [255, 0, 0, 0]),
                                  ([0, 1, 0, 0], [128, 127, 0, 0])])                    # 24 bytes
    sparse_idx = bytes([2, 0, 0, 0])                                                     # 4 bytes
    sparse_val = np.array([0, 0, 3], np.float32).tobytes()                               # 12 bytes
    blob = pos + inter + sparse_idx + sparse_val
    gltf = G.GLTF2(
        scene=0, scenes=[G.Scene(nodes=[0, 1])],
        nodes=[G.Node(mesh=0, skin=0, translation=[100.0, 0.0, 0.0]),
               G.Node(matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1], children=[2]),
               G.Node(scale=[2.0, 2.0, 2.0])],
        skins=[G.Skin(joints=[1, 2])],
        meshes=[G.Mesh(primitives=[G.Primitive(attributes=G.Attributes(POSITION=0, JOINTS_0=1, WEIGHTS_0=2))])],
        buffers=[G.Buffer(byteLength=len(blob),
                          uri="data:application/octet-stream;base64," + base64.b64encode(blob).decode())],
        bufferViews=[G.BufferView(buffer=0, byteOffset=0, byteLength=36),
                     G.BufferView(buffer=0, byteOffset=36, byteLength=24, byteStride=8),
                     G.BufferView(buffer=0, byteOffset=60, byteLength=4),
                     G.BufferView(buffer=0, byteOffset=64, byteLength=12)],
        accessors=[G.Accessor(bufferView=0, componentType=5126, count=3, type="VEC3", min=[0, 0, 0],
                              max=[1, 1, 3],
                              sparse=G.Sparse(count=1,
                                              indices=G.AccessorSparseIndices(bufferView=2, componentType=5121),
                                              values=G.AccessorSparseValues(bufferView=3))),
                   G.Accessor(bufferView=1, byteOffset=0, componentType=5121, count=3, type="VEC4"),
                   G.Accessor(bufferView=1, byteOffset=4, componentType=5121, normalized=True, count=3,
                              type="VEC4")])
    path = tmp_path / "handmade.gltf"
    gltf.save(str(path))
    assert np.allclose(R.bind_positions(path), [[1, 0, 0], [0, 1, 0], [0, 0, 3]])
    # joint 0: translate (0, 0, 1); joint 1: translate (0, 0, 1) @ scale 2
    z = (128 * 4 + 127 * 7) / 255
    assert np.allclose(R.reference_skin(path), [[1, 0, 1], [0, 2, 1], [0, 0, z]], atol=1e-15)
