"""Animations of a glTF document (spec 3.11): channels of skeleton nodes -> ``Clip``s."""
from __future__ import annotations

import numpy as np

from ..animation.clip import CHANNEL_PATHS, INTERPOLATIONS, Channel, Clip
from ._gltf_constants import COMPONENT_NAMES, INPUT_RESIDUALS, OUTPUT_RESIDUALS
from ._gltf_document import _GltfFile
from ._residuals import with_residuals


# --- animations -----------------------------------------------------------------------------------

def _read_clips(f: _GltfFile, node_to_skeleton: dict) -> list[Clip]:
    clips = []
    skipped = {"weights": 0, "other": 0}
    for a, anim in enumerate(f.items("animations")):
        name = anim.name if isinstance(anim.name, str) and anim.name else f"clip{a}"
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
                raise f.error(f"{where}: key times hold non-finite values")
            steps = np.diff(times)
            if (steps <= 0).any():
                i = int(np.flatnonzero(steps <= 0)[0])
                raise f.error(f"{where}: key times must increase strictly, but key {i + 1} "
                              f"(t={times[i + 1]}) follows t={times[i]}")
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
                raise f.error(f"{where}: keyframe values hold non-finite numbers")
            if per_key == 3:
                values = values.reshape(k, 3, width)  # (in-tangent, value, out-tangent) per key
            channels.append(Channel(node=node_to_skeleton[node], path=path, interpolation=interpolation,
                                    times=times, values=values))
        clips.append(Clip(name=name, channels=tuple(channels)))
    if skipped["weights"] or skipped["other"]:
        f.warn(f"skipped {skipped['weights']} animation channels of morph-target weights and "
               f"{skipped['other']} of nodes outside the skeleton (cgaskin animates skeleton nodes only)")
    return clips
