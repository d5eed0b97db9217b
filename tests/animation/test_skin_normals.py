"""Skinned normals are the blended linear part's inverse transpose applied (against numpy), also when
a bone mirrors the mesh (issue 10, item 5: the cofactor matrix alone turned them inside out)."""
import numpy as np
import pytest

import cgaskin


def _reference(rig, pose, normals):
    affines = pose.bone_affines().reshape(-1, 3, 4)
    lin = np.einsum("nk,nkij->nij", rig.weights, affines[rig.joints][..., :3])
    out = np.einsum("nji,nj->ni", np.linalg.inv(lin), normals)          # M^-T n
    return out / np.linalg.norm(out, axis=1, keepdims=True)


@pytest.mark.parametrize("scale", [(1.0, 1.0, 1.0), (-1.0, 1.0, 1.0), (2.0, -0.5, 1.0), (-1.0, -1.0, -1.0)])
def test_normals_follow_the_inverse_transpose_under_any_scale(scale):
    rig = cgaskin.capsule_arm()
    sk = rig.skeleton
    scales = sk.rest_scales.copy()
    scales[0] = scale
    pose = cgaskin.Pose.from_trs(sk, sk.rest_translations, sk.rest_rotations, scales)
    normals = rig.attributes["NORMAL"]
    got = cgaskin.skin_normals(rig, pose)
    np.testing.assert_allclose(got, _reference(rig, pose, normals), atol=1e-12)
