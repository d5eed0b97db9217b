"""Caps of a cut (cgaskin.cut(..., cap=True)): outward normals, nested loops filled by even-odd, open
boundaries in the plane left open.
"""
import numpy as np
import pytest

import cgaskin
from cgaskin import Rig, capsule_arm, cut_details, rig_topology
from cgaskin.surgery.cut import CAP_VERTEX
from cgaskin.surgery.topology import topology

from tests.helpers.cut_checks import chain_skeleton, check_cut, model, volume


def test_cap_normals_face_outwards():
    rig = capsule_arm()
    for pose in (None, rig.pose("wave", 0.6)):
        result = cut_details(rig, [1, 0.1, 0], [1.4, 0, 0], pose=pose, cap=True)
        for h, src, sign in zip((result.positive, result.negative), result.sources, (-1, 1)):
            caps = src == CAP_VERTEX
            assert caps.any()
            normals = cgaskin.skin_normals(h, pose)[caps] if pose is not None else h.attributes["NORMAL"][caps]
            assert np.allclose(normals, sign * result.plane[:3], atol=1e-9)


def test_nested_loops_are_capped_by_even_odd():
    """Two concentric spheres (a hollow ball, inner one inward) and a third inside: the cap of a cut
    through the centre is an annulus plus a disc."""
    trimesh = pytest.importorskip("trimesh")
    parts = []
    for radius, flip in ((3.0, False), (2.0, True), (1.0, False)):
        s = trimesh.creation.icosphere(subdivisions=3, radius=radius)
        faces = np.asarray(s.faces)[:, ::-1] if flip else np.asarray(s.faces)
        parts.append((np.asarray(s.vertices), faces))
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.concatenate([v for v, _ in parts])
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)])
    n = len(vertices)
    rig = Rig(vertices=vertices, faces=faces.astype(np.int64), joints=np.zeros((n, 4), np.int64),
              weights=np.tile([1.0, 0, 0, 0], (n, 1)), skeleton=chain_skeleton(1, np.random.default_rng(1)))
    result = cut_details(rig, [0.1, 0.2, 1.0], [0.01, 0.02, 0.03], cap=True)
    check_cut(rig, result, closed=True, capped=True)
    total = volume(result.positive.vertices, result.positive.faces) + volume(result.negative.vertices,
                                                                              result.negative.faces)
    assert total == pytest.approx(volume(vertices, faces), rel=1e-12)
    assert volume(vertices, faces) > 0


def test_open_boundary_in_the_plane_is_not_capped(models_dir):
    rig = model(models_dir, "Arm5.glb")          # 37 boundary edges (welded) before any cut
    before = len(rig_topology(rig).boundary_edges)
    result = cut_details(rig, [1, 0.3, 0.2], rig.vertices.mean(axis=0), cap=True)
    after = sum(len(topology(h.vertices, h.faces).boundary_edges) for h in (result.positive, result.negative))
    assert after == before


@pytest.mark.parametrize("shift", [1e8, 1e10])
def test_caps_close_the_halves_far_from_the_origin(models_dir, shift):
    """Issue 10, item 3: a posed capped cut of the Fox moved 1e8 away left the halves open, at 1e10
    without any cap: the cap now uses the cut's own on-plane bookkeeping and section coordinates."""
    fox = model(models_dir, "Fox.glb")
    faces = []
    for offset in (0.0, shift):
        pose = fox.rest_pose().translate(0, [offset] * 3)
        point = cgaskin.skin(fox, pose).mean(axis=0)
        result = cut_details(fox, [0, 1, 0.2], point, pose=pose, cap=True)
        for half in (result.positive, result.negative):
            assert len(topology(half.vertices, half.faces).boundary_edges) == 0      # closed
        faces.append([result.positive.n_faces, result.negative.n_faces])
    assert faces[0] == faces[1]


def test_collinear_loop_vertices_make_no_zero_area_cap_triangle(models_dir):
    """Issue 10, item 3: a plane through a flat part of the mesh gives a loop with a run of collinear
    vertices; ear clipping fanned them into triangles of zero area."""
    rig = model(models_dir, "3Cylinder4bones.glb")
    normal = [-1.2992598701307787, 1.265543092596161, 0.4771785779139319]
    result = cut_details(rig, normal, rig.vertices[486], cap=True)
    diag = np.linalg.norm(np.ptp(rig.vertices, axis=0))
    for half, sources in zip((result.positive, result.negative), result.sources):
        v, f = half.vertices, half.faces
        caps = (sources[f] == CAP_VERTEX).all(axis=1)
        areas = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
        assert caps.any() and areas[caps].min() > 1e-9 * diag ** 2
        assert len(topology(v, f).boundary_edges) == 0                       # still closed
