#!/usr/bin/env bash
# Install what the tests need beyond pip: the assimp command line (FBX/DAE), the real clients that
# tests/clients open cgaskin's files in: three.js in headless Chromium (Debian chromium, npm three +
# puppeteer-core, no browser download) and Blender as a module (bpy, Python 3.11 only, in a virtual
# environment of its own: \$CGASKIN_BLENDER_VENV, default ~/.cache/cgaskin/bpy-5.0.1), and what
# tests/targets runs the generated C, GLSL and WGSL with, all on the CPU: a C compiler, glslang's
# validator, Mesa's EGL/llvmpipe OpenGL 4.5 (GLSL compute with fp64) and lavapipe Vulkan (WebGPU).
# Idempotent: when everything is there it only checks (a few seconds).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python}"
JS=tests/clients/js

# --- Debian packages ----------------------------------------------------------------------------
missing=()
command -v assimp >/dev/null 2>&1 || missing+=(assimp-utils)
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
command -v cc >/dev/null 2>&1 || missing+=(gcc libc6-dev)
command -v c++ >/dev/null 2>&1 || missing+=(g++)
command -v glslangValidator >/dev/null 2>&1 || missing+=(glslang-tools)
command -v spirv-val >/dev/null 2>&1 || missing+=(spirv-tools)
# Mesa: EGL + llvmpipe (moderngl's headless GL 4.5) and lavapipe (wgpu's Vulkan adapter)
for pkg in libegl1 libegl-mesa0 libgl1-mesa-dri mesa-vulkan-drivers libvulkan1; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "install-test-deps: apt-get install ${missing[*]}"
    sudo=""
    [ "$(id -u)" = 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# --- npm: three and puppeteer-core at the versions pinned in $JS/package-lock.json ----------------
# (puppeteer-core never downloads a browser: the tests drive /usr/bin/chromium)
if ! (cd "$JS" && node -e '
    const want = require("./package.json").dependencies;
    for (const [name, version] of Object.entries(want))
        if (require(`./node_modules/${name}/package.json`).version !== version) process.exit(1);
' >/dev/null 2>&1); then
    echo "install-test-deps: npm ci in $JS"
    (cd "$JS" && npm ci --no-audit --no-fund --loglevel=error)
fi

# --- Blender as a Python module, in a virtual environment of its own -----------------------------------
# (bpy 5.0.1 requires NumPy < 2, the newest pyarrow NumPy >= 2: one environment cannot hold both; the
# Blender tests run bpy in a subprocess of this environment's Python, tests/clients/conftest.py)
BLENDER_VENV="${CGASKIN_BLENDER_VENV:-$HOME/.cache/cgaskin/bpy-5.0.1}"
if "$PYTHON" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
    if ! "$BLENDER_VENV/bin/python" -c 'import importlib.metadata as m, sys; sys.exit(m.version("bpy") != "5.0.1")' 2>/dev/null; then
        echo "install-test-deps: bpy==5.0.1 into $BLENDER_VENV (about 375 MB)"
        "$PYTHON" -m venv --clear "$BLENDER_VENV"
        "$BLENDER_VENV/bin/python" -m pip install -q bpy==5.0.1
    fi
    # what runs in it besides bpy: cgaskin itself (editable, this checkout) with its run-time deps under
    # Blender 5.0's NumPy (tests/blender: the extension's install test, and tests/surgery again under
    # NumPy 1.26) and what tests/surgery imports. numba and llvmlite at the versions the NumPy 1.26 layer of
    # shipped kernels was built for, where it is there (else Blender would compile every kernel); the
    # rest as pip resolves it with NumPy pinned. Checked first: when all is there, no pip runs.
    venv_wants=(numpy==1.26.4 pygltflib pytest hypothesis clifford trimesh manifold3d sympy galgebra)
    layer_versions="$("$BLENDER_VENV/bin/python" -c '
import json, pathlib
for manifest in sorted(pathlib.Path("runtime/_kernels").glob("*-numpy1.26/manifest.json")):
    built_for = json.loads(manifest.read_text())["built_for"]
    print("numba==" + built_for["numba"], "llvmlite==" + built_for["llvmlite"])
    break
else:
    print("numba")')"
    read -r -a layer_versions <<< "$layer_versions"
    venv_wants+=("${layer_versions[@]}")
    if ! "$BLENDER_VENV/bin/python" - "$(pwd)" "${venv_wants[@]}" <<'PY' 2>/dev/null; then
import importlib.metadata as m, importlib.util, sys
repo, wants = sys.argv[1], sys.argv[2:]
for want in wants:                      # "name" or "name==version"
    name, _, version = want.partition("==")
    if version and m.version(name) != version:
        sys.exit(1)
    m.version(name)                     # raises when absent
spec = importlib.util.find_spec("cgaskin")
sys.exit(not (spec and spec.origin.startswith(repo + "/runtime/")))
PY
        echo "install-test-deps: ${venv_wants[*]} and cgaskin (editable) into $BLENDER_VENV"
        "$BLENDER_VENV/bin/python" -m pip install -q "${venv_wants[@]}"
        "$BLENDER_VENV/bin/python" -m pip install -q --no-deps -e .
    fi
else
    echo "install-test-deps: bpy 5.0.1 needs Python 3.11, this is $("$PYTHON" -V 2>&1):" \
         "the Blender tests cannot run here (they skip, and fail under CGASKIN_CI=1)" >&2
fi
echo "install-test-deps: assimp, chromium, three, puppeteer-core, cc, glslang, Mesa EGL/lavapipe$("$PYTHON" -c 'import sys; print(", bpy" if sys.version_info[:2] == (3, 11) else "")') ready"
