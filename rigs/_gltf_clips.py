"""Animations of a glTF document (spec 3.11): channels of skeleton nodes -> ``Clip``s."""
from __future__ import annotations

import numpy as np

from ..animation.clip import CHANNEL_PATHS, INTERPOLATIONS, Channel, Clip
from ..errors import ModelFormatError
from ._gltf_constants import COMPONENT_NAMES, INPUT_RESIDUALS, OUTPUT_RESIDUALS
from ._gltf_document import _GltfFile
from ._residuals import with_residuals


# --- animations -----------------------------------------------------------------------------------

class _BrokenKeys(ModelFormatError):
    """An animation's key times or values are unusable (NaN, infinite, not increasing): that
    animation is dropped, the model loads. A malformed document (a bad index, accessor type or
    cgaskin residual) is still an error of the whole file."""


def _read_clips(f: _GltfFile, node_to_skeleton: dict) -> list[Clip]:
    """One ``Clip`` per animation. An animation whose key times or values are broken (NaN,
    infinite, not increasing) is dropped with a warning that names it and says what is wrong: the
    mesh, the skeleton and the other clips do not depend on it, so they still load."""
    clips = []
    skipped = {"weights": 0, "other": 0}
    for a, anim in enumerate(f.items("animations")):
        name = anim.name if isinstance(anim.name, str) and anim.name else f"clip{a}"
        try:
            clips.append(_read_clip(f, a, anim, name, node_to_skeleton, skipped))
        except _BrokenKeys as exc:
            reason = str(exc).removeprefix(f"{f.path.name}: ").removeprefix(f"animation {a} ({name!r}) ")
            f.warn(f"dropped animation {a} ({name!r}): {reason}; the mesh, the skeleton and the "
                   f"other animations are loaded")
    if skipped["weights"] or skipped["other"]:
        f.warn(f"skipped {skipped['weights']} animation channels of morph-target weights and "
               f"{skipped['other']} of nodes outside the skeleton (cgaskin animates skeleton nodes only)")
    return clips


def _read_clip(f: _GltfFile, a: int, anim, name: str, node_to_skeleton: dict, skipped: dict) -> Clip:
    """The ``Clip`` of animation ``a``; ``_BrokenKeys`` when the keys of a channel are unusable,
    ModelFormatError when the document is malformed."""
    samplers = anim.samplers or []
    channels = []
    for c, ch in enumerate(anim.channels or []):
        where = f"animation {a} ({name!r}) channel {c}"
        target = ch.target
        path = getattr(target, "path", None)
        node = getattr(target, "node", None)
        if path == "weights":
            skipped["weights"] += 1
            continue
        if path not in CHANNEL_PATHS or node not in node_to_skeleton:
            if node is not None:
                f.index(node, "nodes", f"{where} target node")
            skipped["other"] += 1
            continue
        if isinstance(ch.sampler, bool) or not isinstance(ch.sampler, int) or not 0 <= ch.sampler < len(samplers):
            raise f.error(f"{where} sampler {ch.sampler!r} is out of range ({len(samplers)} samplers)")
        sampler = samplers[ch.sampler]
        interpolation = sampler.interpolation or "LINEAR"
        if interpolation not in INTERPOLATIONS:
            raise f.error(f"{where}: unknown interpolation {interpolation!r}; glTF allows "
                          f"{', '.join(INTERPOLATIONS)}")
        _, ttype, tshape, k = f.accessor_info(sampler.input, f"{where} input")
        if ttype != 5126 or tshape != "SCALAR":
            raise f.error(f"{where}: key times must be SCALAR float, got {tshape} {COMPONENT_NAMES[ttype]}")
        times = f.accessor(sampler.input, f"{where} input")
        # written by save_gltf: float64 times and values exactly (residuals in the sampler's extras)
        times = with_residuals(f, sampler, INPUT_RESIDUALS, times, f"{where} sampler {ch.sampler}")
        if not np.isfinite(times).all():
            k = int(np.flatnonzero(~np.isfinite(times))[0])
            raise f.error(f"{where}: key times hold non-finite values (key {k}: t={times[k]}; "
                          f"{int((~np.isfinite(times)).sum())} of {len(times)} keys)", cls=_BrokenKeys)
        steps = np.diff(times)
        if (steps <= 0).any():
            i = int(np.flatnonzero(steps <= 0)[0])
            raise f.error(f"{where}: key times must increase strictly, but key {i + 1} "
                          f"(t={times[i + 1]}) follows t={times[i]}", cls=_BrokenKeys)
        width = CHANNEL_PATHS[path]
        _, vtype, vshape, vcount = f.accessor_info(sampler.output, f"{where} output")
        if vshape != f"VEC{width}":
            raise f.error(f"{where}: {path} values must be VEC{width}, got {vshape}")
        per_key = 3 if interpolation == "CUBICSPLINE" else 1
        if vcount != per_key * k:
            raise f.error(f"{where}: {k} key times need {per_key * k} {interpolation} output "
                          f"values, the output accessor has {vcount}")
        values = f.accessor(sampler.output, f"{where} output")
        if values.dtype != np.float64:
            raise f.error(f"{where}: {path} values must be float or normalized integers, got "
                          f"{COMPONENT_NAMES[vtype]}")
        values = with_residuals(f, sampler, OUTPUT_RESIDUALS, values, f"{where} sampler {ch.sampler}")
        if not np.isfinite(values).all():
            raise f.error(f"{where}: keyframe values hold non-finite numbers", cls=_BrokenKeys)
        if per_key == 3:
            values = values.reshape(k, 3, width)  # (in-tangent, value, out-tangent) per key
        channels.append(Channel(node=node_to_skeleton[node], path=path, interpolation=interpolation,
                                times=times, values=values))
    return Clip(name=name, channels=tuple(channels))
