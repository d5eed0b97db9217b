"""glTF 2.0 constants of the loader and exporter: component types, accessor shapes, GLB chunk
tags, primitive modes, and the loader's limits and tolerances (a table module, no logic)."""
from __future__ import annotations

import numpy as np

# --- glTF constants (spec 3.6.2) ---------------------------------------------------------------
COMPONENT_DTYPES = {
    5120: np.dtype("<i1"),  # BYTE
    5121: np.dtype("<u1"),  # UNSIGNED_BYTE
    5122: np.dtype("<i2"),  # SHORT
    5123: np.dtype("<u2"),  # UNSIGNED_SHORT
    5125: np.dtype("<u4"),  # UNSIGNED_INT
    5126: np.dtype("<f4"),  # FLOAT
}
COMPONENT_NAMES = {5120: "byte", 5121: "unsigned byte", 5122: "short", 5123: "unsigned short",
                   5125: "unsigned int", 5126: "float"}
#: (columns, rows) of each accessor type; vectors are a single column
TYPE_SHAPES = {"SCALAR": (1, 1), "VEC2": (1, 2), "VEC3": (1, 3), "VEC4": (1, 4),
               "MAT2": (2, 2), "MAT3": (3, 3), "MAT4": (4, 4)}
#: spec 3.11 "normalized" integers: f = max(c / (2^(bits-1) - 1), -1) signed, c / (2^bits - 1) unsigned
NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
INTEGER_INDEX_TYPES = (5121, 5123, 5125)

GLB_MAGIC = b"glTF"
GLB_JSON_CHUNK = 0x4E4F534A
GLB_BIN_CHUNK = 0x004E4942

MODE_NAMES = {0: "POINTS", 1: "LINES", 2: "LINE_LOOP", 3: "LINE_STRIP", 4: "TRIANGLES",
              5: "TRIANGLE_STRIP", 6: "TRIANGLE_FAN"}
#: extensions that change how geometry is stored: files that require them cannot be read here
UNSUPPORTED_EXTENSIONS = {"KHR_draco_mesh_compression", "EXT_meshopt_compression",
                          "KHR_meshopt_compression"}
#: an accessor without bufferView is materialised as zeros: refuse absurd counts (a corrupted
#: file must not make us allocate gigabytes)
MAX_BUFFERLESS_COMPONENTS = 1 << 26
#: quaternions further than this from unit length are renormalised; closer ones are kept as
#: stored so that a save -> load round trip is exact (renormalising is not idempotent in floats)
QUAT_UNIT_TOLERANCE = 1e-12
#: cgaskin's data in a primitive's ``extras`` (accessor indices, never vertex attributes: see
#: export.py): the float64 positions' rounding residuals, POSITION + LO + LO2 == the float64
#: vertices exactly, and the float64 weights', (WEIGHTS_n + LO) + LO2 == the weights of set n
EXTRAS_KEY = "cgaskin"
POSITION_RESIDUALS = ("POSITION_LO", "POSITION_LO2")
WEIGHT_RESIDUALS = ("WEIGHTS_{}_LO", "WEIGHTS_{}_LO2")
#: the same in a skin's ``extras["cgaskin"]`` (inverseBindMatrices + LO + LO2 == the float64
#: inverse bind matrices) and in an animation sampler's (input / output + LO + LO2 == the float64
#: key times / values)
INVERSE_BIND_RESIDUALS = ("INVERSE_BIND_LO", "INVERSE_BIND_LO2")
INPUT_RESIDUALS = ("INPUT_LO", "INPUT_LO2")
OUTPUT_RESIDUALS = ("OUTPUT_LO", "OUTPUT_LO2")
#: where earlier versions of cgaskin kept the weight residuals: application-specific vertex
#: attributes (custom semantics start with "_"); still read, no longer written
LEGACY_WEIGHT_RESIDUALS = ("_CGASKIN_WEIGHTS_{}_LO", "_CGASKIN_WEIGHTS_{}_LO2")
#: in ``extras["cgaskin"]``: {"_NAME": width} of the application attributes that ``save_gltf``
#: zero-padded to the width of the widest (Blender imports "_" attributes of one width only)
ATTRIBUTE_WIDTHS = "ATTRIBUTE_WIDTHS"
#: inverse bind matrices and node matrices must be affine: last row (0, 0, 0, 1) within this
AFFINE_TOLERANCE = 1e-6
#: in ``extras["cgaskin"]``: {"_NAME": rig name} of the attributes written under another name
#: than the rig's because glTF has no place for theirs ("FOO" -> "_FOO"; ``_gltf_attributes``)
ATTRIBUTE_NAMES = "ATTRIBUTE_NAMES"
#: in a node's ``extras["cgaskin"]``: the index of the node it duplicates. ``save_gltf`` writes one
#: such child (no transform, no children) per further bone of a skeleton node that several bones
#: share with different inverse bind matrices (skins merged on loading); the loader folds it back
JOINT_OF = "JOINT_OF"
