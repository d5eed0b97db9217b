#!/usr/bin/env bash
# Build the Blender extension: one installable archive per platform, dist/cgaskin-<version>-<platform>.zip
# (named as Blender's builder names them: dist/cgaskin-0.1.0-linux_x64.zip).
#
#   bash scripts/build-blender-extension.sh [--platforms linux-x64,...] [--numba V] [--llvmlite V]
#        [--pygltflib V] [--numpy 1.26] [--cgaskin-wheel FILE]... [--output-dir dist]
#
# 1. a cgaskin wheel from this working tree (`pip wheel --no-deps` of a copy of the package's sources),
#    carrying the shipped kernel layers for Blender's NumPy (--numpy, default 1.26: Blender 5.0's);
# 2. numba, llvmlite (default: the versions in the bpy venv, $CGASKIN_BLENDER_VENV) and pygltflib with
#    its run-time dependencies, as CPython 3.11 wheels for each platform (cached in
#    ~/.cache/cgaskin/wheels); never NumPy: Blender bundles its own and a second one breaks Blender;
# 3. the add-on's files (blender/cgaskin_blender, without __pycache__) staged with the wheels and the
#    manifest, its `wheels` and `platforms` filled in (scripts/stage_blender_extension.py);
# 4. zipped by Blender's own builder (bl_pkg/cli/blender_ext.py build --split-platforms, from the bpy
#    wheel), which validates the manifest and keeps in each platform's archive only that platform's wheels.
#
# The platforms default to the manifest's `platforms`. cgaskin's wheel is machine code too (its kernels):
# this machine builds the one for its own platform; another platform's (built there with `pip wheel`)
# comes in with --cgaskin-wheel. Only linux-x64 is built and tested here (tests/blender).
# Idempotent; a second run downloads nothing (about 10 s, mostly the wheel's build).
set -euo pipefail
cd "$(dirname "$0")/.."
REPO="$(pwd)"
PYTHON="${PYTHON:-python}"
BLENDER_VENV="${CGASKIN_BLENDER_VENV:-$HOME/.cache/cgaskin/bpy-5.0.1}"
BLENDER_PYTHON="$BLENDER_VENV/bin/python"
WHEEL_CACHE="${CGASKIN_WHEEL_CACHE:-$HOME/.cache/cgaskin/wheels}"
ADDON="${CGASKIN_BLENDER_ADDON:-$REPO/blender/cgaskin_blender}"   # another folder: a trial build
WORK="$REPO/build/blender-extension"

platforms="" numba="" llvmlite="" pygltflib="" numpy="1.26" output="$REPO/dist" extra_wheels=()
while [ $# -gt 0 ]; do
    case "$1" in
        --platforms) platforms="$2"; shift 2 ;;
        --numba) numba="$2"; shift 2 ;;
        --llvmlite) llvmlite="$2"; shift 2 ;;
        --pygltflib) pygltflib="$2"; shift 2 ;;
        --numpy) numpy="$2"; shift 2 ;;
        --cgaskin-wheel) extra_wheels+=("$(realpath "$2")"); shift 2 ;;
        --output-dir) output="$(realpath -m "$2")"; shift 2 ;;
        -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
        *) echo "build-blender-extension: unknown argument $1 (--help lists them)" >&2; exit 2 ;;
    esac
done

fail() { echo "build-blender-extension: $*" >&2; exit 1; }
[ -x "$BLENDER_PYTHON" ] || fail "no bpy venv at $BLENDER_VENV (bash scripts/install-test-deps.sh): its Python runs Blender's builder"
BUILDER="$(ls "$BLENDER_VENV"/lib/python3.11/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py 2>/dev/null | head -n1)"
[ -n "$BUILDER" ] || fail "Blender's extension builder (bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py) is not in $BLENDER_VENV"
[ -f "$ADDON/__init__.py" ] || fail "the add-on has no $ADDON/__init__.py yet"

# versions: what the bpy venv runs (the shipped layer was built for its numba and llvmlite), unless given
installed() { "$BLENDER_PYTHON" -c 'import importlib.metadata as m, sys; print(m.version(sys.argv[1]))' "$1" 2>/dev/null \
              || fail "$1 is not installed in $BLENDER_VENV: give its version (--$1 V)"; }
numba="${numba:-$(installed numba)}"
llvmlite="${llvmlite:-$(installed llvmlite)}"
pygltflib="${pygltflib:-$(installed pygltflib)}"
version="$("$BLENDER_PYTHON" -c 'import tomllib; print(tomllib.load(open("pyproject.toml", "rb"))["project"]["version"])')"
platforms="${platforms:-$("$BLENDER_PYTHON" -c 'import sys, tomllib; print(",".join(tomllib.load(open(sys.argv[1], "rb"))["platforms"]))' "$ADDON/blender_manifest.toml")}"

# pip's platform tags for a Blender platform (wheels for CPython 3.11, the Python of Blender 4.2 to 5.0)
pip_platforms() {
    case "$1" in
        linux-x64) echo "manylinux_2_28_x86_64 manylinux_2_17_x86_64 manylinux2014_x86_64" ;;
        linux-arm64) echo "manylinux_2_28_aarch64 manylinux_2_17_aarch64 manylinux2014_aarch64" ;;
        windows-x64) echo "win_amd64" ;;
        windows-arm64) echo "win_arm64" ;;
        macos-arm64) echo "macosx_11_0_arm64" ;;
        macos-x64) echo "macosx_10_15_x86_64 macosx_10_9_x86_64" ;;
        *) fail "no pip platform tags known for the Blender platform $1" ;;
    esac
}

IFS=',' read -r -a platform_list <<< "$platforms"
for platform in "${platform_list[@]}"; do pip_platforms "$platform" >/dev/null; done
rm -rf "$WORK" && mkdir -p "$WORK" "$WHEEL_CACHE" "$output"
SECONDS=0

# --- 1. cgaskin's wheel, from a copy of what the package is built from -------------------------------
# (a copy: setuptools' build/ folder in the tree would keep files since deleted from the sources, and
# only the layers for Blender's NumPy travel: another NumPy's layer would be 13 MB never loaded)
src="$WORK/cgaskin-src"
mkdir -p "$src"
cp pyproject.toml setup.py README.md "$src/"
for folder in runtime codegen generated rigs; do
    (cd "$REPO" && find "$folder" -name __pycache__ -prune -o -path 'runtime/_kernels' -prune -o -type f -print) \
        | (cd "$REPO" && xargs -d '\n' cp --parents -t "$src")
done
layers=0
for layer in runtime/_kernels/*-numpy"$numpy"; do
    [ -f "$layer/manifest.json" ] || continue
    cp -r --parents "$layer" "$src/"
    layers=$((layers + 1))
done
[ "$layers" -gt 0 ] || fail "no shipped kernel layer for NumPy $numpy in runtime/_kernels (the bpy venv's \`python -m cgaskin build --kernels\` builds it): Blender would compile every kernel at first use"
"$PYTHON" -m pip wheel -q --no-deps --wheel-dir "$WORK/cgaskin-wheel" "$src" > "$WORK/wheel.log" 2>&1 \
    || { tail -n 40 "$WORK/wheel.log" >&2; fail "pip wheel failed (the whole log: $WORK/wheel.log)"; }
wheels=("$WORK"/cgaskin-wheel/cgaskin-*.whl "${extra_wheels[@]}")

# --- 2. numba, llvmlite, pygltflib and its dependencies for each platform -------------------------------
# pip download prints where each file is ("Saved ..." / "File was already downloaded ..."): those files,
# not the whole cache, are this build's. The cache alone (--no-index) answers a second run.
download() {   # download <blender platform> <pip arguments>...
    local tags=() tag
    for tag in $(pip_platforms "$1"); do tags+=(--platform "$tag"); done
    shift
    local args=(download -d "$WHEEL_CACHE" --only-binary :all: "${tags[@]}" --python-version 3.11
                --implementation cp --abi cp311 "$@")
    { "$PYTHON" -m pip "${args[@]}" --no-index --find-links "$WHEEL_CACHE" 2>/dev/null \
      || "$PYTHON" -m pip "${args[@]}" 2>> "$WORK/download.log"; } \
        | sed -n -E 's/^ *(Saved|File was already downloaded) (.*\.whl)$/\2/p'
}
listed="$WORK/downloaded.txt"
: > "$listed"
for platform in "${platform_list[@]}"; do
    { download "$platform" --no-deps "numba==$numba" "llvmlite==$llvmlite" \
      && download "$platform" "pygltflib==$pygltflib"; } >> "$listed" \
        || { grep -v '^WARNING: Location' "$WORK/download.log" | tail -n 20 >&2; fail "pip download failed for $platform"; }
done
while IFS= read -r file; do wheels+=("$(realpath "$file")"); done < "$listed"

# --- 3. staged: the add-on, the wheels, the manifest ------------------------------------------------
"$BLENDER_PYTHON" scripts/stage_blender_extension.py --addon "$ADDON" --stage "$WORK/stage" --version "$version" \
    --builder "$BUILDER" --platforms "$platforms" --wheels "${wheels[@]}"

# --- 4. Blender's builder: validates the manifest, one archive per platform -------------------------
for platform in "${platform_list[@]}"; do rm -f "$output/cgaskin-$version-${platform//-/_}.zip"; done
"$BLENDER_PYTHON" "$BUILDER" build --source-dir "$WORK/stage" --output-dir "$output" --split-platforms
for platform in "${platform_list[@]}"; do
    archive="$output/cgaskin-$version-${platform//-/_}.zip"
    [ -f "$archive" ] || fail "Blender's builder did not write $archive"
    echo "build-blender-extension: $archive ($(du -h "$archive" | cut -f1))"
done
echo "build-blender-extension: built in ${SECONDS} s"
