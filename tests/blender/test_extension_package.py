"""The extension's archive (``bash scripts/build-blender-extension.sh``): what it bundles, and that it
installs into a fresh Blender profile through Blender's own operator, where its add-on is enabled in a
new Blender process, uses the bundled cgaskin (not the bpy venv's editable one) and runs a first cut
from the shipped kernels, compiling nothing. (About 15 s: the build, warm, 5 s; Blender twice.)"""
import json
import os
import subprocess
import textwrap
import tomllib
import zipfile
from pathlib import Path

import pytest

import cgaskin
from tests.clients.conftest import SUMMARY
from tests.helpers.compile_events import RECORD_COMPILES

REPO = Path(__file__).resolve().parents[2]

#: the module Blender gives an extension installed into the default user repository
ADDON = "bl_ext.user_default.cgaskin"
OPERATORS = ("cut", "tear", "drill", "revert")
#: the wheels every linux-x64 archive carries (normalised names); NumPy is Blender's own
BUNDLED = {"cgaskin", "numba", "llvmlite", "pygltflib"}

# process 1: install the archive as a user would (Edit > Preferences > Get Extensions > Install from Disk)
# and save the preferences, which remember the add-on as enabled
INSTALL = textwrap.dedent("""\
    import json, sys
    import bpy
    done = bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo="user_default",
                                                    enable_on_install=True)
    bpy.ops.wm.save_userpref()
    print(json.dumps({"done": sorted(done), "addons": sorted(bpy.context.preferences.addons.keys())}))
""")

# process 2, a new Blender with that profile: what is enabled and registered, where cgaskin and numba come
# from, what the first cut loads and compiles (numba's compile events), and how long it takes
CHECK = textwrap.dedent("""\
    import json, sys, time, tomllib
    start = time.perf_counter()
    import bpy
    # Blender as a module starts with the factory preferences; the application reads the profile's
    # userpref.blend at startup, which enables the add-ons saved as enabled: the same, done here
    bpy.ops.wm.read_userpref()
    started = time.perf_counter() - start
    addon = sys.argv[1]
    enabled = addon in bpy.context.preferences.addons
    registered = {}
    for name in sys.argv[2].split(","):
        try:
            registered[name] = getattr(bpy.ops.cgaskin, name).get_rna_type().identifier
        except (AttributeError, KeyError):
            registered[name] = None
""") + RECORD_COMPILES + textwrap.dedent("""\
    import numba, cgaskin
    from cgaskin._shared import shipped
    start = time.perf_counter()
    upper, lower = cgaskin.cut(cgaskin.capsule_arm(), [1, 0, 0], [1.5, 0, 0])
    first = time.perf_counter() - start
    manifest = tomllib.loads(open(sys.argv[3], encoding="utf-8").read())
    bpy.ops.preferences.addon_disable(module=addon)
    unregistered = [name for name in sys.argv[2].split(",") if hasattr(bpy.types, f"CGASKIN_OT_{name}")]
    print(json.dumps({
        "enabled": enabled, "registered": registered, "unregistered": unregistered,
        "cgaskin": cgaskin.__file__, "numba": numba.__file__, "version": cgaskin.__version__,
        "manifest_version": manifest["version"], "layer": str(shipped._layer()[0] and shipped._layer()[0].folder),
        "loaded": sum(shipped.LOADED.values()), "compiled": sorted(set(compiled)),
        "faces": [len(upper.faces), len(lower.faces)], "started": started, "first_cut": first}))
""")


def bpy_run(blender: str, script: str, args: list, profile: Path, cache: Path, cwd: Path) -> dict:
    """Run ``script`` with Blender's Python in the profile ``profile`` (BLENDER_USER_RESOURCES: config,
    scripts, extensions) and the empty numba cache ``cache``; its last line of output, as JSON."""
    environment = {key: value for key, value in os.environ.items()
                   if not key.startswith(("NUMBA_", "BLENDER_USER_", "CGASKIN_SHIPPED"))}
    environment.update(BLENDER_USER_RESOURCES=str(profile), NUMBA_CACHE_DIR=str(cache))
    done = subprocess.run([blender, "-c", script, *args], capture_output=True, text=True, env=environment,
                          cwd=cwd, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1]) | {"stderr": done.stderr}


@pytest.fixture(scope="module")
def extension_zip(blender, tmp_path_factory) -> Path:
    """The linux-x64 archive, built once by the repository's script into a temporary folder (its wheel
    downloads are cached in ~/.cache/cgaskin/wheels); the build's time and the archive's size are reported."""
    out = tmp_path_factory.mktemp("extension")
    done = subprocess.run(["bash", str(REPO / "scripts" / "build-blender-extension.sh"), "--platforms", "linux-x64",
                           "--output-dir", str(out)], capture_output=True, text=True, cwd=REPO, timeout=900)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (archive,) = out.glob("cgaskin-*-linux_x64.zip")
    SUMMARY.append(f"{done.stdout.strip().splitlines()[-1]}: {archive.name} {archive.stat().st_size / 2**20:.1f} MiB")
    return archive


def wheels_in(archive: zipfile.ZipFile) -> dict:
    """normalised distribution name -> wheel file name, for the archive's ./wheels/."""
    names = [Path(n).name for n in archive.namelist() if n.startswith("wheels/") and n.endswith(".whl")]
    return {n.split("-")[0].lower().replace("_", "-"): n for n in names}


def test_the_archive_bundles_cgaskin_with_its_kernels_for_numpy_1_26_and_no_numpy(extension_zip):
    """Named as Blender's builder names a platform's archive; its manifest is cgaskin's version for
    linux-x64 and lists exactly the wheels it carries: cgaskin (with the NumPy 1.26 layer only),
    numba, llvmlite, pygltflib and its dependencies, no NumPy."""
    assert extension_zip.name == f"cgaskin-{cgaskin.__version__}-linux_x64.zip"
    with zipfile.ZipFile(extension_zip) as archive:
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        wheels = wheels_in(archive)
        assert "__init__.py" in archive.namelist()
        assert not [n for n in archive.namelist() if "__pycache__" in n]
        with archive.open(f"wheels/{wheels['cgaskin']}") as inner, zipfile.ZipFile(inner) as wheel:
            layers = {n.split("/")[2] for n in wheel.namelist() if n.startswith("cgaskin/_kernels/")}
    assert manifest["id"] == "cgaskin" and manifest["version"] == cgaskin.__version__
    assert manifest["platforms"] == ["linux-x64"] and manifest["blender_version_min"] == "4.3.0"
    assert manifest["license"] == ["SPDX:Apache-2.0"] and manifest["type"] == "add-on"
    assert sorted(manifest["wheels"]) == sorted(f"./wheels/{w}" for w in wheels.values())
    assert BUNDLED <= set(wheels) and "numpy" not in wheels, wheels
    assert layers == {"cp311-linux_x86_64-numpy1.26"}, layers
    assert wheels["cgaskin"].endswith("-linux_x86_64.whl")


@pytest.fixture(scope="module")
def installed(blender, extension_zip, tmp_path_factory) -> Path:
    """A fresh Blender profile with the archive installed by Blender's operator and the add-on enabled."""
    profile = tmp_path_factory.mktemp("profile")
    result = bpy_run(blender, INSTALL, [str(extension_zip)], profile, tmp_path_factory.mktemp("install-cache"),
                     tmp_path_factory.mktemp("install-cwd"))
    assert result["done"] == ["FINISHED"] and ADDON in result["addons"], result
    return profile


def test_the_installed_extension_runs_the_bundled_cgaskin_from_its_shipped_kernels(blender, installed, tmp_path):
    """In a new Blender process the add-on is enabled and its operators registered (and gone when it is
    disabled); cgaskin and numba are the bundled ones (the bpy venv's editable cgaskin loses to the
    extension's site-packages, which Blender puts first); the manifest says cgaskin's version; a first
    cut loads its kernels from the shipped layer and numba compiles nothing (no compile event, the
    numba cache stays empty)."""
    cache = tmp_path / "numba-cache"
    cache.mkdir()
    extensions = installed / "extensions"
    result = bpy_run(blender, CHECK, [ADDON, ",".join(OPERATORS),
                                      str(extensions / "user_default" / "cgaskin" / "blender_manifest.toml")],
                     installed, cache, tmp_path)
    bundled = str(extensions / ".local" / "lib" / "python3.11" / "site-packages")
    assert result["enabled"], result
    assert result["registered"] == {name: f"CGASKIN_OT_{name}" for name in OPERATORS}, result
    assert result["unregistered"] == [], result
    assert result["cgaskin"].startswith(bundled + "/cgaskin/"), result["cgaskin"]
    assert result["numba"].startswith(bundled + "/numba/"), result["numba"]
    assert result["layer"].startswith(bundled + "/cgaskin/_kernels/"), result["layer"]
    assert result["version"] == result["manifest_version"] == cgaskin.__version__
    assert result["loaded"] > 0 and result["compiled"] == [], result
    assert min(result["faces"]) > 0, result
    assert sorted(p.name for p in cache.rglob("*") if p.suffix in (".nbi", ".nbc")) == []
    SUMMARY.append(f"installed extension: Blender started with it in {result['started']:.2f} s, first cut "
                   f"{result['first_cut']:.2f} s ({result['loaded']} kernels loaded from the shipped layer, 0 compiled)")
