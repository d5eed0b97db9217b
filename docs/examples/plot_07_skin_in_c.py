"""
Skin in C (or a GLSL shader) from the generated files
=====================================================

The kernels that skin in Python are printed for other targets too: C99 headers, GLSL, WGSL, CUDA
and JavaScript, shipped in ``cgaskin.generated`` (``cgaskin build --target ...`` writes them again).
Skinning is two stages: per bone, the bone's versor becomes a 3x4 affine map
(``cgaskin_bone_affines``); per vertex, the maps of its joints are blended by its weights and applied
once (``cgaskin_skin_blend``). Here both stages run in C, compiled at build time with the system's C
compiler through cffi, and skin the capsule arm as ``cgaskin.skin`` does.
"""
import shutil
import subprocess
import tempfile
from importlib import resources
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin import versor
from cgaskin.app.render import render_strip

headers = resources.files("cgaskin.generated.c")
skin_h = headers.joinpath("cgaskin_skin.h").read_text()
print(skin_h[skin_h.index("/* affines"):skin_h.index("CGASKIN_API void cgaskin_skin_vertex")])

# %%
# A pose's bones as versors: the global transform of each bone's joint times its inverse bind
# matrix (for the capsule arm both are similarities, so each product is a versor).
rig = cgaskin.capsule_arm()
pose = rig.pose("wave", 0.7).dilate("wrist", 1.3)
bone_matrices = pose.global_matrices()[rig.skeleton.bone_nodes] @ rig.skeleton.inverse_bind
bone_versors = np.ascontiguousarray(versor.from_matrix(bone_matrices))

# %%
# Compile the headers into a shared library (``CGASKIN_API`` empty: external functions) and call the
# two stages on numpy arrays, without copies.
cc = shutil.which("cc") or shutil.which("gcc")
try:
    import cffi
except ImportError:
    cffi = None
if cc and cffi:
    build = Path(tempfile.mkdtemp())
    for name in ("cgaskin.h", "cgaskin_skin.h"):
        (build / name).write_text(headers.joinpath(name).read_text())
    (build / "skin.c").write_text('#define CGASKIN_API\n#include "cgaskin_skin.h"\n')
    subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-shared", "-fPIC", str(build / "skin.c"),
                    "-o", str(build / "libskin.so"), "-lm"], check=True)
    ffi = cffi.FFI()
    ffi.cdef("""
        typedef struct { size_t bad_joints; size_t bad_weights; size_t bad_values; } cgaskin_skin_counts;
        void cgaskin_bone_affines(size_t n_bones, const double *versors, double *affines);
        cgaskin_skin_counts cgaskin_skin_blend(size_t n, size_t k, const double *rest, const int32_t *joints,
            const double *weights, size_t n_bones, const double *affines, double *out);
    """)
    lib = ffi.dlopen(str(build / "libskin.so"))
    rest = np.ascontiguousarray(rig.vertices, np.float64)
    joints = np.ascontiguousarray(rig.joints, np.int32)
    weights = np.ascontiguousarray(rig.weights, np.float64)
    affines = np.empty((len(bone_versors), 12))
    skinned = np.empty_like(rest)
    lib.cgaskin_bone_affines(len(bone_versors), ffi.from_buffer("double[]", bone_versors),
                             ffi.from_buffer("double[]", affines))
    counts = lib.cgaskin_skin_blend(len(rest), joints.shape[1], ffi.from_buffer("double[]", rest),
                                    ffi.from_buffer("int32_t[]", joints), ffi.from_buffer("double[]", weights),
                                    len(affines), ffi.from_buffer("double[]", affines),
                                    ffi.from_buffer("double[]", skinned))
    expected = cgaskin.skin(rig, pose)
    print("bad joints, weights, values:", counts.bad_joints, counts.bad_weights, counts.bad_values)
    print("max |C - cgaskin.skin| =", np.abs(skinned - expected).max())
    render_strip([(expected, rig.faces), (skinned, rig.faces)], "skin_in_c.png",
                 titles=["cgaskin.skin", "the generated C"], columns=2, size=3.5)
else:
    print("no C compiler or no cffi here: the C is shown, not run")

# %%
# The same two stages for the GPU: ``cgaskin_skin_bones.comp`` and ``cgaskin_skin.comp`` are GLSL
# compute shaders over flat std430 buffers, ``cgaskin_skin.vert`` a vertex shader reading a buffer of
# maps, and ``cgaskin_skin_webgl.glsl`` the GLSL ES 3.00 chunk that the viewer's page runs in WebGL2.
glsl = resources.files("cgaskin.generated.glsl")
print(sorted(path.name for path in glsl.iterdir() if path.name.endswith((".glsl", ".comp", ".vert"))))
vert = glsl.joinpath("cgaskin_skin.vert").read_text()
print(vert[vert.index("vec3 cgaskin_skin_vertex"):])
