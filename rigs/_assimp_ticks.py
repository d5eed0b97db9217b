"""Key times of animations whose source gives 0 ticks per second, recovered as assimp plays them.

assimp keeps key times in ticks and an animation's ticks per second (``mTicksPerSecond``); a source
may leave them at 0 (a DirectX ``.x`` file without ``AnimTicksPerSecond``, or with 0). The glTF
exporter divides by them regardless, so every key time of such an animation becomes NaN or
infinity and the glTF loader drops the clip. assimp's own viewer plays 0 ticks per second as 25
(``tools/assimp_view/AnimEvaluator.cpp``: ``mAnim->mTicksPerSecond != 0.0 ? ... : 25.0``); so
does cgaskin: the times in ticks are read from assimp's XML dump of the source (``_assimp_dump``)
and written over the broken ones in the converted file, with a warning that says so.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pygltflib

from .._shared.warn import warn
from ..errors import ModelWarning

__all__ = ["DEFAULT_TICKS_PER_SECOND", "repair_key_times"]

#: what assimp's viewer plays an animation with 0 ticks per second at
DEFAULT_TICKS_PER_SECOND = 25.0

_ANIMATION = re.compile(r'<Animation name="(.*?)" duration="[^"]*" tick_cnt="([^"]*)">(.*?)</Animation>', re.S)
_NODE = re.compile(r'<NodeAnim node="(.*?)">(.*?)</NodeAnim>', re.S)
_KEYS = {"translation": re.compile(r'<PositionKey time="([^"]*)"'),
         "rotation": re.compile(r'<RotationKey time="([^"]*)"'),
         "scale": re.compile(r'<ScalingKey time="([^"]*)"')}


def _untimed_animations(assxml: str) -> dict:
    """{animation index: (name, {(node name, glTF path): key times in ticks})} of the animations
    of an assxml dump whose ticks per second are 0."""
    out = {}
    for a, (name, ticks_per_second, body) in enumerate(_ANIMATION.findall(assxml)):
        try:
            if float(ticks_per_second) != 0.0:
                continue
        except ValueError:
            continue
        keys = {}
        for node, channel in _NODE.findall(body):
            for path, pattern in _KEYS.items():
                times = pattern.findall(channel)
                if times:
                    keys[(node, path)] = np.array(times, dtype=np.float64)
        out[a] = (name, keys)
    return out


def repair_key_times(glb: Path, assxml: str, source: str) -> bool:
    """Rewrite, in the converted ``glb``, the key times of each animation whose ticks per second
    are 0 as ticks / 25 s, where the dump holds the same keys (animation name, node name, path,
    count); True when any animation was repaired (with a warning naming it and ``source``)."""
    untimed = _untimed_animations(assxml)
    if not untimed:
        return False
    gltf = pygltflib.GLTF2.load(str(glb))
    blob = bytearray(gltf.binary_blob() or b"")
    repaired = []
    for a, animation in enumerate(gltf.animations or []):
        if a not in untimed or untimed[a][0] != (animation.name or ""):
            continue
        keys, fixed = untimed[a][1], False
        for channel in animation.channels:
            sampler = animation.samplers[channel.sampler]
            node = gltf.nodes[channel.target.node].name if channel.target.node is not None else None
            ticks = keys.get((node, channel.target.path))
            if ticks is None or len(ticks) != gltf.accessors[sampler.input].count:
                continue
            times = (ticks / DEFAULT_TICKS_PER_SECOND).astype("<f4")
            if not (np.isfinite(times).all() and (np.diff(times) > 0).all()):
                continue
            blob += b"\0" * (-len(blob) % 4)
            gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=len(blob),
                                                         byteLength=times.nbytes))
            blob += times.tobytes()
            gltf.accessors.append(pygltflib.Accessor(
                bufferView=len(gltf.bufferViews) - 1, byteOffset=0, componentType=pygltflib.FLOAT,
                count=len(times), type=pygltflib.SCALAR, min=[float(times.min())], max=[float(times.max())]))
            sampler.input = len(gltf.accessors) - 1   # a new accessor: other samplers keep theirs
            fixed = True
        if fixed:
            repaired.append(animation.name or f"clip{a}")
    if not repaired:
        return False
    gltf.buffers[0].byteLength = len(blob)
    gltf.set_binary_blob(bytes(blob))
    gltf.save_binary(str(glb))
    warn(f"{source}: animation{'s' if len(repaired) > 1 else ''} {', '.join(map(repr, repaired))} "
         f"give{'' if len(repaired) > 1 else 's'} 0 ticks per second (or none): played at "
         f"{DEFAULT_TICKS_PER_SECOND:g} ticks per second, as assimp's viewer plays them", ModelWarning)
    return True
