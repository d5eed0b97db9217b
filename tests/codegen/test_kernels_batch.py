"""Every generated kernel has an oracle test (a ``covers`` mark in tests/codegen/test_kernels_*.py), and
every kernel's batch form computes its scalar form row by row.
"""
from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest

from cgaskin.generated import kernels as K
from cgaskin.generated import skinning as SK
from tests.helpers import strategies as S
from tests.helpers.kernel_oracles import COVERED


def test_every_kernel_is_tested():
    # the family modules' @covers marks fill COVERED when they are imported (already, in a full run)
    for path in sorted(Path(__file__).parent.glob("test_kernels_*.py")):
        importlib.import_module(f"{__package__}.{path.stem}")
    skinning = {name for name in dir(SK) if name.startswith("skin_") and callable(getattr(SK, name))}
    missing = (set(K.KERNEL_NAMES) | skinning) - COVERED
    assert not missing, f"kernels without an oracle test: {sorted(missing)}"


# ==== batch forms ============================================================================================
_RNG = np.random.default_rng(11)
_SIMS = [S.Similarity(ax / np.linalg.norm(ax), ang, t, s) for ax, ang, t, s in zip(
    _RNG.normal(size=(5, 3)), _RNG.uniform(-6, 6, 5), _RNG.uniform(-100, 100, (5, 3)), np.exp(_RNG.uniform(-4, 4, 5)))]


def _batch_inputs(name):
    vs = np.stack([s.versor() for s in _SIMS])
    pts = _RNG.uniform(-50, 50, (5, 3))
    normals = _RNG.normal(size=(5, 3))
    planes = np.column_stack([normals / np.linalg.norm(normals, axis=1, keepdims=True), _RNG.uniform(-9, 9, 5)])
    return {
        "versor_translator": (pts,),
        "versor_rotor": (_RNG.normal(size=(5, 3)), _RNG.uniform(-6, 6, 5)),
        "versor_rotor_quaternion": (_RNG.normal(size=(5, 4)),),
        "versor_dilator": (np.exp(_RNG.uniform(-4, 4, 5)),),
        "versor_from_matrix": (np.stack([s.matrix().ravel() for s in _SIMS]),),
        "gp_motor_motor": (vs[:, :8], vs[::-1, :8].copy()),
        "gp_versor_versor": (vs, vs[::-1].copy()),
        "reverse_versor": (vs,), "inverse_versor": (vs,), "versor_residual": (vs,),
        "versor_normalise": (vs * 1.7,), "versor_to_affine": (vs,), "versor_log": (vs,),
        "sandwich_versor_point": (vs, pts),
        "affine_point": (_RNG.normal(size=(5, 12)), pts),
        "plane_from_normal_distance": (_RNG.normal(size=(5, 3)), _RNG.uniform(-9, 9, 5)),
        "plane_from_points": (pts, pts + _RNG.normal(size=(5, 3)), pts + _RNG.normal(size=(5, 3))),
        "plane_transform": (vs, planes),
        "point_plane_distance": (planes, pts),
        "segment_plane": (planes, pts, -pts),
        "point_line_distance": (pts, _RNG.normal(size=(5, 3)), pts[::-1] + _RNG.normal(size=(5, 3))),
        "barycentric": (pts, pts + _RNG.normal(size=(5, 3)), pts + _RNG.normal(size=(5, 3)), pts + 0.3),
        "versor_exp": (_RNG.normal(size=(5, 7)),),
    }[name]


# (plane_from_normal_distance_batch used to shadow its input `n` with the row index: fixed in b5db720)
@pytest.mark.parametrize("name", K.KERNEL_NAMES)
def test_batch_kernel_matches_scalar(name):
    args = _batch_inputs(name)
    scalar = getattr(K, name)
    rows = [np.atleast_1d(np.asarray(scalar(*(a[i] for a in args)), float)) for i in range(5)]
    expected = np.stack(rows)
    out = np.empty(expected.shape)
    getattr(K, name + "_batch")(*args, out)
    np.testing.assert_array_equal(out, expected)
