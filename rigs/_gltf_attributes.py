"""Per-vertex attributes other than positions, joints and weights (spec 3.7.2.1), both ways.

Names. A rig's ``attributes`` keys map to glTF attribute semantics one to one, so that every
attribute reloads under its own name (which also decides how cut and tear interpolate it, see
``cgaskin.surgery.new_vertices.attribute_rule``):

* a glTF semantic whose accessor type the spec allows for the array's width keeps its name:
  ``NORMAL`` (n, 3), ``TANGENT`` (n, 4), ``TEXCOORD_n`` (n, 2), ``COLOR_n`` (n, 3) or (n, 4);
* an application-specific name (leading ``_``, e.g. the tear's ``_TEAR``) keeps its name;
* any other name (``FOO``, or ``NORMAL`` of width 2, ``POSITION``, ``JOINTS_0``: the spec has no
  place for them) is written as ``_FOO`` (``_FOO_2``, ``_FOO_3``, ... when the rig holds a
  ``_FOO`` too), and ``extras["cgaskin"]["ATTRIBUTE_NAMES"]`` of the primitive maps the written
  name back to the rig's name. Other readers see a valid application-specific attribute.

Values. Written as float32 (the spec's float accessors); read from float or normalized integer
accessors (``TEXCOORD_n`` and ``COLOR_n`` may be normalized unsigned byte/short, quantized files
normalize others too). Application-specific attributes are zero-padded to one common width for
Blender (see export.py); their true widths are kept in ``extras["cgaskin"]["ATTRIBUTE_WIDTHS"]``.
"""
from __future__ import annotations

import re

import numpy as np

from ..errors import InvalidInputError
from ._gltf_constants import (ATTRIBUTE_NAMES, ATTRIBUTE_WIDTHS, COMPONENT_NAMES, EXTRAS_KEY,
                              LEGACY_WEIGHT_RESIDUALS)

__all__ = ["semantic_widths", "gltf_attribute_names", "read_attributes"]

_INDEXED = re.compile(r"(TEXCOORD|COLOR|JOINTS|WEIGHTS)_(0|[1-9][0-9]*)")
#: widths (accessor VECn) the spec allows for the semantics cgaskin carries as attributes
_WIDTHS = {"NORMAL": (3,), "TANGENT": (4,), "TEXCOORD": (2,), "COLOR": (3, 4)}
#: semantics the spec defines that are no ``Rig.attributes`` entry (read into other fields)
_GEOMETRY = ("POSITION", "JOINTS", "WEIGHTS")
#: names earlier versions of cgaskin wrote for weight residuals (read as such, never attributes)
_LEGACY = {name.format(s) for name in LEGACY_WEIGHT_RESIDUALS for s in range(8)}


def _base(name: str) -> str:
    match = _INDEXED.fullmatch(name)
    return match.group(1) if match else name


def semantic_widths(name: str) -> tuple:
    """The widths glTF allows for attribute ``name`` as cgaskin reads it: () for an
    application-specific name (any width 1..4), None when it is no attribute cgaskin carries
    (POSITION, JOINTS_n, WEIGHTS_n, or no glTF semantic at all)."""
    if name.startswith("_"):
        return None if name in _LEGACY else ()
    return _WIDTHS.get(_base(name))


# --- writing ---------------------------------------------------------------------------------------

def gltf_attribute_names(rig_attributes: dict, n: int) -> tuple[dict, dict]:
    """The attributes to write, and the names to restore on reading (see the module docstring).

    rig_attributes : {name: (n,) or (n, 1..4) array}
    returns : ({glTF name: (n, c) float64}, {glTF name: rig name} of the renamed ones)
    Raises InvalidInputError for a name that is no string or an array of the wrong shape.
    """
    arrays = {}
    for name, values in rig_attributes.items():
        if not isinstance(name, str) or not name:
            raise InvalidInputError(f"attribute name {name!r} must be a non-empty string")
        values = np.asarray(values)
        if values.ndim == 1:
            values = values[:, None]
        if values.ndim != 2 or len(values) != n or values.shape[1] not in (1, 2, 3, 4):
            raise InvalidInputError(f"attribute {name!r} has shape {values.shape}; vertex attributes "
                                    f"are ({n}, 1..4)")
        arrays[name] = values
    # names that are written as they are come first, so that a renamed one never takes theirs
    kept = {name for name, values in arrays.items()
            if (widths := semantic_widths(name)) is not None and (not widths or values.shape[1] in widths)}
    out, renamed, used = {}, {}, kept | _LEGACY  # never a name the loader reads as residuals
    for name, values in arrays.items():
        written = name
        if name not in kept:
            written, k = "_" + name, 1
            while written in used:
                k += 1
                written = f"_{name}_{k}"
            used.add(written)
            renamed[written] = name
        out[written] = values
    return out, renamed


# --- reading ---------------------------------------------------------------------------------------

def read_attributes(f, prim, attrs: dict, where: str) -> dict:
    """{rig name: (n, c) float64} of a primitive's attributes other than POSITION, JOINTS_n and
    WEIGHTS_n: padding trimmed (``ATTRIBUTE_WIDTHS``), names restored (``ATTRIBUTE_NAMES``).
    Attributes glTF does not define (no leading ``_``) are ignored with a warning."""
    ours = prim.extras.get(EXTRAS_KEY) if isinstance(prim.extras, dict) else None
    ours = ours if isinstance(ours, dict) else {}
    widths = _name_map(f, ours, ATTRIBUTE_WIDTHS, where, lambda w: type(w) is int and 1 <= w <= 4,
                       "widths 1..4")
    names = _name_map(f, ours, ATTRIBUTE_NAMES, where, lambda v: isinstance(v, str) and v, "names")
    out, unknown = {}, []
    for name, accessor in attrs.items():
        allowed = semantic_widths(name)
        if allowed is None:
            if _base(name) not in _GEOMETRY and name not in _LEGACY:
                unknown.append(name)
            continue
        _, ctype, atype, _ = f.accessor_info(accessor, f"{where} {name}")
        values = f.accessor(accessor, f"{where} {name}")
        if values.ndim == 1:
            values = values[:, None]
        if (values.ndim != 2 or (allowed and values.shape[1] not in allowed)
                or values.dtype != np.float64):
            shapes = "/".join(f"VEC{w}" for w in allowed) or "SCALAR/VECn"
            raise f.error(f"{where} {name} must be {shapes} of floats or normalized integers, got "
                          f"{atype} {COMPONENT_NAMES[ctype]}")
        if not np.isfinite(values).all():
            v = int(np.flatnonzero(~np.isfinite(values).all(axis=1))[0])
            raise f.error(f"{where} {name} holds non-finite values (vertex {v}: {values[v].tolist()})")
        if name in widths:  # zero-padded by save_gltf to the width of the other "_" attributes
            values = values[:, :widths[name]]
        out[name] = values
    if unknown:
        f.warn(f"{where}: ignored attributes {', '.join(map(repr, sorted(unknown)))}: they are no "
               f"glTF 2.0 semantic (application-specific attributes start with '_')")
    restored = {names.get(name, name): values for name, values in out.items()}
    if len(restored) != len(out):
        raise f.error(f"{where} extras.{EXTRAS_KEY}.{ATTRIBUTE_NAMES} maps two attributes to one "
                      f"name: {names!r}")
    return restored


def _name_map(f, ours: dict, key: str, where: str, valid, what: str) -> dict:
    value = ours.get(key, {})
    if not isinstance(value, dict) or not all(isinstance(k, str) and valid(v) for k, v in value.items()):
        raise f.error(f"{where} extras.{EXTRAS_KEY}.{key} must map attribute names to {what}, "
                      f"got {value!r}")
    return value
