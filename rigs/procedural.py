"""Procedural rigs: models built in code, for the demo and for tests that need no files.

``capsule_arm`` is a closed capsule along +x driven by a chain of joints, with smooth two-bone weights
and a short "wave" clip. Everything is computed from the arguments alone (no randomness), so two calls
give bit-identical rigs.
"""
from __future__ import annotations

import math

import numpy as np

from ..animation.clip import Channel, Clip
from ..animation.rig import Rig
from .._shared.memory_budget import require_memory
from ..animation.skeleton import Skeleton
from ..errors import InvalidInputError

#: the memory the capsule takes per vertex as it is made (positions, normals, joints, weights, two
#: faces, and the temporaries of the rings and of the rig's checks), and per joint (its skeleton
#: rows, its clip's keys)
_VERTEX_BYTES, _JOINT_BYTES = 480, 2048

__all__ = ["capsule_arm"]


def _quat_axis_angle(axis, degrees):
    """Unit quaternions (x, y, z, w) for rotations by ``degrees`` (k,) about a unit ``axis`` (3,)."""
    half = np.radians(np.asarray(degrees, dtype=np.float64)) / 2
    return np.concatenate([np.sin(half)[:, None] * np.asarray(axis, float)[None, :],
                           np.cos(half)[:, None]], axis=1)


def _translation(t):
    m = np.eye(4)
    m[:3, 3] = t
    return m


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def _profile(n_joints, length, radius, rings_per_segment, cap_rings):
    """Rings of the capsule from the -x pole to the +x pole.

    returns (x (r,), ring radius (r,), normal x-component (r,), normal radial component (r,)),
    first and last entries being the poles (radius 0)
    """
    # Left hemisphere: polar angle phi from the -x pole (phi = 0) to the equator (phi = pi/2, which is
    # the first cylinder ring, so it is not repeated here).
    phi = np.arange(cap_rings) * (np.pi / 2) / cap_rings
    left_x, left_r = -radius * np.cos(phi), radius * np.sin(phi)
    left_nx, left_nr = -np.cos(phi), np.sin(phi)
    # Cylinder from x = 0 to x = length, rings_per_segment quads per bone segment.
    cyl_x = np.linspace(0.0, length, n_joints * rings_per_segment + 1)
    ones = np.ones_like(cyl_x)
    x = np.concatenate([left_x, cyl_x, length - left_x[::-1]])
    r = np.concatenate([left_r, radius * ones, left_r[::-1]])
    nx = np.concatenate([left_nx, 0 * ones, -left_nx[::-1]])
    nr = np.concatenate([left_nr, ones, left_nr[::-1]])
    return x, r, nx, nr


def _capsule_mesh(n_joints, length, radius, rings_per_segment, segments_around):
    """Vertices (n, 3), outward normals (n, 3) and CCW-outward faces (m, 3) of a closed capsule."""
    cap_rings = max(2, segments_around // 4)
    x, r, nx, nr = _profile(n_joints, length, radius, rings_per_segment, cap_rings)
    theta = np.arange(segments_around) * (2 * np.pi / segments_around)
    cos_t, sin_t = np.cos(theta), np.sin(theta)

    # Vertex 0 is the -x pole, then (rings - 2) full rings, then the +x pole.
    inner = slice(1, len(x) - 1)
    ring_v = np.stack([np.repeat(x[inner], segments_around),
                       np.outer(r[inner], cos_t).ravel(),
                       np.outer(r[inner], sin_t).ravel()], axis=1)
    ring_n = np.stack([np.repeat(nx[inner], segments_around),
                       np.outer(nr[inner], cos_t).ravel(),
                       np.outer(nr[inner], sin_t).ravel()], axis=1)
    vertices = np.concatenate([[[x[0], 0.0, 0.0]], ring_v, [[x[-1], 0.0, 0.0]]])
    normals = np.concatenate([[[-1.0, 0.0, 0.0]], ring_n, [[1.0, 0.0, 0.0]]])
    n_rings = len(x) - 2
    last_pole = len(vertices) - 1

    def ring(k):
        return 1 + k * segments_around + np.arange(segments_around)

    # Winding: with the ring parameterised as (x, r cos θ, r sin θ), +θ points along +z at θ = 0 and
    # the outward normal along +y, and z × x = +y. So a triangle turning from +θ to +x is CCW seen
    # from outside: (a_j, a_j+1, b_j+1) and (a_j, b_j+1, b_j) for ring a followed by ring b in +x.
    faces = []
    a0 = ring(0)
    faces.append(np.stack([np.zeros(segments_around, np.int64), np.roll(a0, -1), a0], axis=1))
    for k in range(n_rings - 1):
        a, b = ring(k), ring(k + 1)
        a1, b1 = np.roll(a, -1), np.roll(b, -1)
        faces.append(np.stack([a, a1, b1], axis=1))
        faces.append(np.stack([a, b1, b], axis=1))
    last = ring(n_rings - 1)
    faces.append(np.stack([last, np.roll(last, -1), np.full(segments_around, last_pole)], axis=1))
    return vertices, normals, np.concatenate(faces).astype(np.int64)


def _weights(x, n_joints, spacing):
    """Two-bone smooth weights along the axis.

    Bone i covers [i, i + 1) * spacing. A vertex between the midpoints of bones i - 1 and i is shared
    by those two bones, bone i's share rising by a smoothstep from 0 at the first midpoint to 1 at the
    second (so it is 1/2 at joint i, and the weights are C1 along the axis). Before the first midpoint
    and after the last one a vertex follows one bone only.

    returns joints (n, 4) int64, weights (n, 4) float64
    """
    n = len(x)
    joints = np.zeros((n, 4), np.int64)
    weights = np.zeros((n, 4))
    if n_joints == 1:
        weights[:, 0] = 1.0
        return joints, weights
    # Position in "midpoint units": bone i's midpoint sits at u = i.
    u = np.clip(x / spacing - 0.5, 0.0, n_joints - 1.0)
    lower = np.minimum(np.floor(u), n_joints - 2).astype(np.int64)
    w_upper = _smoothstep(u - lower)
    joints[:, 0], joints[:, 1] = lower, lower + 1
    weights[:, 0], weights[:, 1] = 1.0 - w_upper, w_upper
    # Canonical layout (the one validate.check_mesh produces): weighted slots first, unused slots
    # name bone 0, so that the rig passes validation unchanged.
    unused = weights == 0
    order = np.argsort(unused, axis=1, kind="stable")
    joints = np.where(unused, 0, joints)
    return np.take_along_axis(joints, order, 1), np.take_along_axis(weights, order, 1)


def _wave_clip(n_joints):
    """Two seconds of waving: the root sways, the next joint bends, further joints flick and twist."""
    times = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    z = np.array([0.0, 0.0, 1.0])
    channels = []
    for i in range(n_joints):
        if i == 0:
            q = _quat_axis_angle(z, [0.0, 25.0, 0.0, -25.0, 0.0])
        elif i == 1:
            q = _quat_axis_angle(z, [0.0, 45.0, 90.0, 45.0, 0.0])
        else:
            bend = _quat_axis_angle(z, [0.0, -30.0, 0.0, 30.0, 0.0])
            twist = _quat_axis_angle(np.array([1.0, 0.0, 0.0]), [0.0, 20.0, 40.0, 20.0, 0.0])
            # bend after twist: q = bend * twist (Hamilton product, (x, y, z, w))
            bv, bw = bend[:, :3], bend[:, 3:]
            tv, tw = twist[:, :3], twist[:, 3:]
            q = np.concatenate([bw * tv + tw * bv + np.cross(bv, tv),
                                bw * tw - np.sum(bv * tv, axis=1, keepdims=True)], axis=1)
        channels.append(Channel(node=i, path="rotation", interpolation="LINEAR",
                                times=times.copy(), values=q))
    return Clip(name="wave", channels=tuple(channels))


def capsule_arm(n_joints=3, length=3.0, radius=0.25, rings_per_segment=12, segments_around=16) -> Rig:
    """A capsule along +x skinned to a chain of joints: the built-in demo and test rig.

    The capsule is the set of points within ``radius`` of the segment from x = 0 to x = ``length``:
    a cylinder with hemispherical caps beyond both ends. The joints sit at x = i * length / n_joints
    (root at the origin), so each bone, the last one included, drives a segment of equal length.
    Joint names are "shoulder", "elbow", "wrist" for three joints, else "joint0", "joint1", ...

    n_joints : int >= 1
    length : float > 0, length of the cylindrical part
    radius : float > 0
    rings_per_segment : int >= 1, rings of quads per bone segment along the cylinder
    segments_around : int >= 3, vertices per ring

    returns Rig with
        vertices (n, 3) float64, n = segments_around * (n_joints * rings_per_segment + 2 * cap - 1) + 2
            with cap = max(2, segments_around // 4) (690 for the defaults)
        faces (m, 3) int64, closed, manifold, counter-clockwise seen from outside
        joints, weights (n, 4): at most two non-zero influences, summing to 1
        attributes {"NORMAL": (n, 3) float64 unit outward normals}
        skeleton: rest pose = bind pose; inverse_bind[i] = inverse of joint i's global bind matrix
        clips [Clip "wave"]: LINEAR rotation keys on every joint over 2 s
    """
    if isinstance(n_joints, bool) or not isinstance(n_joints, (int, np.integer)) or n_joints < 1:
        raise InvalidInputError(f"n_joints must be an integer >= 1, got {n_joints!r}")
    for name, value in (("length", length), ("radius", radius)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value) and value > 0):
            raise InvalidInputError(f"{name} must be a finite number > 0, got {value!r}")
    for name, value, least in (("rings_per_segment", rings_per_segment, 1),
                               ("segments_around", segments_around, 3)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise InvalidInputError(f"{name} must be an integer >= {least}, got {value!r}")
    n_joints, rings_per_segment, segments_around = int(n_joints), int(rings_per_segment), int(segments_around)
    length, radius = float(length), float(radius)
    n_vertices = segments_around * (n_joints * rings_per_segment + 2 * max(2, segments_around // 4) - 1) + 2
    require_memory(n_vertices * _VERTEX_BYTES + n_joints * _JOINT_BYTES,
                   f"capsule_arm(n_joints={n_joints}, rings_per_segment={rings_per_segment}, segments_around="
                   f"{segments_around}) ({n_vertices} vertices)", "give fewer joints, rings or segments")

    vertices, normals, faces = _capsule_mesh(n_joints, length, radius, rings_per_segment, segments_around)
    spacing = length / n_joints
    joints, weights = _weights(vertices[:, 0], n_joints, spacing)

    names = ["shoulder", "elbow", "wrist"] if n_joints == 3 else [f"joint{i}" for i in range(n_joints)]
    parents = np.arange(-1, n_joints - 1, dtype=np.int64)
    translations = np.zeros((n_joints, 3))
    translations[1:, 0] = spacing          # each child one segment further along +x
    rotations = np.tile([0.0, 0.0, 0.0, 1.0], (n_joints, 1))
    scales = np.ones((n_joints, 3))
    local = np.array([_translation(t) for t in translations])
    # Pure translations along one axis: the global bind matrix of joint i is a translation by
    # i * spacing, and its inverse is exact.
    inverse_bind = np.array([_translation([-i * spacing, 0.0, 0.0]) for i in range(n_joints)])

    skeleton = Skeleton(names=names, parents=parents, rest_translations=translations,
                        rest_rotations=rotations, rest_scales=scales, rest_matrices=local,
                        bone_nodes=np.arange(n_joints, dtype=np.int64), inverse_bind=inverse_bind)
    return Rig(vertices=vertices, faces=faces, joints=joints, weights=weights, skeleton=skeleton,
               clips=[_wave_clip(n_joints)], attributes={"NORMAL": normals}, name="capsule_arm")
