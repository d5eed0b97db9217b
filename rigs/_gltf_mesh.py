"""Mesh primitives of a glTF document (spec 3.7 "Geometry"): one primitive -> positions, triangles,
joints and weights (residuals of ``save_gltf`` applied), other attributes (``_gltf_attributes``);
the primitives of all skinned mesh nodes merged into one mesh, joint slots mapped to bones.
"""
from __future__ import annotations

import numpy as np
import pygltflib

from ..errors import NoSkinError
from ._gltf_constants import (COMPONENT_NAMES, INTEGER_INDEX_TYPES,
                              LEGACY_WEIGHT_RESIDUALS, MODE_NAMES, POSITION_RESIDUALS, WEIGHT_RESIDUALS)
from ._gltf_attributes import read_attributes
from ._gltf_document import _GltfFile
from ._residuals import with_residuals


# --- meshes -----------------------------------------------------------------------------------------

def _attribute_map(f: _GltfFile, prim, where: str) -> dict:
    attrs = prim.attributes
    if isinstance(attrs, pygltflib.Attributes):
        attrs = vars(attrs)
    if not isinstance(attrs, dict):
        raise f.error(f"{where}: attributes must be a JSON object, got {attrs!r}")
    return {k: v for k, v in attrs.items() if v is not None}


def _triangles(f: _GltfFile, mode: int, idx: np.ndarray, where: str) -> np.ndarray:
    """Faces (m, 3) int64 of a TRIANGLES / TRIANGLE_STRIP / TRIANGLE_FAN index sequence."""
    n = len(idx)
    if mode == 4:
        if n % 3:
            raise f.error(f"{where}: TRIANGLES needs a multiple of 3 indices/vertices, got {n}")
        return idx.reshape(-1, 3)
    if n < 3:
        return np.zeros((0, 3), dtype=np.int64)
    i = np.arange(n - 2)
    if mode == 5:
        # spec 3.7.2.1: triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), which keeps the winding
        faces = np.stack([idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]], axis=1)
    else:
        faces = np.stack([idx[i + 1], idx[i + 2], np.full(n - 2, idx[0])], axis=1)
    # strips are stitched with degenerate triangles: they carry no surface, drop them
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return faces[keep]


def _read_primitive(f: _GltfFile, m: int, p: int, prim, skinned: bool):
    """Decode one triangle primitive; for points and lines return the mode's name instead.

    returns dict: positions (n, 3) float64, faces (m, 3) int64, joints (n, 4s) int64,
        weights (n, 4s) float64, attributes {name: (n, c) float64}
    """
    where = f"mesh {m} primitive {p}"
    mode = 4 if prim.mode is None else prim.mode
    if mode not in MODE_NAMES:
        raise f.error(f"{where} has unknown mode {mode!r}")
    if mode < 4:
        return MODE_NAMES[mode]
    attrs = _attribute_map(f, prim, where)
    if "POSITION" not in attrs:
        raise f.error(f"{where} has no POSITION attribute")
    _, _, ptype, n = f.accessor_info(attrs["POSITION"], f"{where} POSITION")
    if ptype != "VEC3":
        raise f.error(f"{where} POSITION must be VEC3, got {ptype}")
    for name, acc in attrs.items():
        count = f.accessor_info(acc, f"{where} {name}")[3]
        if count != n:
            raise f.error(f"{where}: attribute {name} has {count} elements but POSITION has {n}; "
                          f"all attributes of a primitive must have one element per vertex")
    positions = f.accessor(attrs["POSITION"], f"{where} POSITION").astype(np.float64)
    bad = ~np.isfinite(positions)
    if bad.any():
        v = int(np.flatnonzero(bad.any(axis=1))[0])
        raise f.error(f"{where} POSITION (accessor {attrs['POSITION']}) holds non-finite coordinates: "
                      f"vertex {v} is {positions[v].tolist()} ({int(bad.any(axis=1).sum())} such vertices)")
    positions = with_residuals(f, prim, POSITION_RESIDUALS, positions, where)

    if prim.indices is not None:
        _, ctype, itype, _ = f.accessor_info(prim.indices, f"{where} indices")
        if ctype not in INTEGER_INDEX_TYPES or itype != "SCALAR":
            raise f.error(f"{where} indices must be SCALAR unsigned byte/short/int, got "
                          f"{itype} {COMPONENT_NAMES[ctype]}")
        idx = f.accessor(prim.indices, f"{where} indices")
        bad = idx >= n
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise f.error(f"{where}: index {int(idx[k])} at position {k} of accessor {prim.indices} "
                          f"is out of range: the primitive has {n} vertices "
                          f"({int(bad.sum())} bad indices)")
    else:
        idx = np.arange(n, dtype=np.int64)  # non-indexed: vertices taken in order
    faces = _triangles(f, mode, idx, where)

    # NORMAL, TANGENT, TEXCOORD_n, COLOR_n and application-specific attributes ("_NAME", e.g. the
    # tear's "_TEAR" labels): carried through cut, tear and export under the rig's names
    out = {"positions": positions, "faces": faces,
           "attributes": read_attributes(f, prim, attrs, where)}

    sets = sorted({int(k.split("_")[1]) for k in attrs
                   if k.split("_")[0] in ("JOINTS", "WEIGHTS") and k.split("_")[-1].isdigit()})
    for s in sets:
        if f"JOINTS_{s}" not in attrs or f"WEIGHTS_{s}" not in attrs:
            raise f.error(f"{where} has only one of JOINTS_{s} / WEIGHTS_{s}; they come in pairs")
    if skinned and 0 not in sets:
        raise f.error(f"{where} belongs to a skinned node but has no JOINTS_0/WEIGHTS_0")
    joints, weights = [], []
    for s in sets:
        _, jtype, jshape, _ = f.accessor_info(attrs[f"JOINTS_{s}"], f"{where} JOINTS_{s}")
        _, wtype, wshape, _ = f.accessor_info(attrs[f"WEIGHTS_{s}"], f"{where} WEIGHTS_{s}")
        j = f.accessor(attrs[f"JOINTS_{s}"], f"{where} JOINTS_{s}")
        w = f.accessor(attrs[f"WEIGHTS_{s}"], f"{where} WEIGHTS_{s}")
        if jshape != "VEC4" or j.dtype != np.int64:
            raise f.error(f"{where} JOINTS_{s} must be VEC4 unsigned byte/short, got "
                          f"{jshape} {COMPONENT_NAMES[jtype]}{' normalized' if j.dtype != np.int64 else ''}")
        if wshape != "VEC4" or w.dtype != np.float64:
            raise f.error(f"{where} WEIGHTS_{s} must be VEC4 float or normalized unsigned "
                          f"byte/short, got {wshape} {COMPONENT_NAMES[wtype]} (not normalized)")
        # written by save_gltf: restore the float64 weights exactly (earlier versions: attributes)
        w = with_residuals(f, prim, [r.format(s) for r in WEIGHT_RESIDUALS], w, where)
        for name in (r.format(s) for r in LEGACY_WEIGHT_RESIDUALS):
            if name in attrs:
                residual = f.accessor(attrs[name], f"{where} {name}")
                if residual.shape != w.shape or residual.dtype != np.float64:
                    raise f.error(f"{where} {name} must be VEC4 float like WEIGHTS_{s}")
                w = w + residual
        joints.append(j)
        weights.append(w)
    out["joints"] = np.concatenate(joints, axis=1) if joints else np.zeros((n, 0), dtype=np.int64)
    out["weights"] = np.concatenate(weights, axis=1) if weights else np.zeros((n, 0))
    return out


def _merge_primitives(f: _GltfFile, skinned: list[tuple[int, int]], slot_maps: dict):
    """Read every triangle primitive of the skinned mesh nodes and merge them into one mesh.

    skinned : [(file node, skin)] in scene order; slot_maps : {skin: (joints,) int64 bone of each
        joint slot}
    returns : vertices (n, 3) float64, faces (m, 3) int64, joints (n, 4s) int64 bone indices,
        weights (n, 4s) float64 (s: the most JOINTS_n/WEIGHTS_n sets of a primitive), attributes
        {name: (n, c) float64} that every primitive has
    """
    nodes = f.items("nodes")
    parts, skipped_modes = [], []
    for i, s in skinned:
        m = nodes[i].mesh
        primitives = f.items("meshes")[m].primitives or []
        for p, prim in enumerate(primitives):
            part = _read_primitive(f, m, p, prim, skinned=True)
            if isinstance(part, str):
                skipped_modes.append(part)
                continue
            j, w = part["joints"], part["weights"]
            slots = slot_maps[s]
            bad = (w > 0) & ((j < 0) | (j >= len(slots)))
            if bad.any():
                v = int(np.flatnonzero(bad.any(axis=1))[0])
                raise f.error(f"mesh {m} primitive {p}: vertex {v} is weighted to joint "
                              f"{int(j[bad][0])} but skin {s} has {len(slots)} joints")
            j = np.where(w > 0, j, 0)  # unused slots may hold anything: point them at slot 0
            part["joints"] = slots[j]
            parts.append(part)
    if skipped_modes:
        f.warn(f"skipped {len(skipped_modes)} primitives that are not triangles "
               f"({', '.join(sorted(set(skipped_modes)))})")
    if not parts:
        raise f.error("the skinned meshes hold no triangle primitive", cls=NoSkinError)

    offsets = np.cumsum([0] + [len(part["positions"]) for part in parts])
    vertices = np.concatenate([part["positions"] for part in parts])
    faces = np.concatenate([part["faces"] + off for part, off in zip(parts, offsets)])
    width = max(part["weights"].shape[1] for part in parts)

    def padded(key, dtype):
        return np.concatenate([np.pad(part[key], ((0, 0), (0, width - part[key].shape[1])))
                               for part in parts]).astype(dtype)

    joints, weights = padded("joints", np.int64), padded("weights", np.float64)
    attributes = {}
    names = dict.fromkeys(name for part in parts for name in part["attributes"])
    for name in names:
        have = [name in part["attributes"] for part in parts]
        if all(have):
            attributes[name] = np.concatenate([part["attributes"][name] for part in parts])
        elif any(have):
            f.warn(f"dropped attribute {name}: only {sum(have)} of {len(parts)} merged primitives have it")
    if len(faces) == 0:
        raise f.error("the skinned meshes hold no triangle (all primitives are empty or degenerate)")
    return vertices, faces, joints, weights, attributes
