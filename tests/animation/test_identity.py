"""Rigs, poses, skeletons and clips are values compared by identity: they can be hashed, put in sets
and compared without numpy's elementwise comparison raising, and per-rig caches let them go."""
import copy
import gc
import weakref

import cgaskin
from cgaskin._shared import cache


def test_rigs_and_poses_compare_by_identity_and_hash():
    rig = cgaskin.capsule_arm()
    twin = copy.copy(rig)
    assert rig == rig and rig != twin and not (rig == twin)
    pose = rig.pose("wave", 0.25)
    assert len({rig, twin, pose, rig.skeleton, rig.clips[0], rig.clips[0].channels[0]}) == 6
    assert {pose: 1}[pose] == 1 and hash(rig) != hash(twin)


def test_per_rig_caches_let_the_rig_go():
    rig = cgaskin.capsule_arm()
    pose = rig.pose("wave", 0.5)
    cgaskin.tear(rig, ([0.6, 0.5, 0.0], [0.6, 0.0, 0.0]), ([0.9, 0.5, 0.0], [0.9, 0.0, 0.0]), pose=pose)
    cgaskin.rig_topology(rig)
    assert rig in cache._CACHE
    gone, pose_gone = weakref.ref(rig), weakref.ref(pose)
    del rig, pose
    gc.collect()
    assert gone() is None and pose_gone() is None
