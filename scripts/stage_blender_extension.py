"""Stage the Blender extension for Blender's builder: the add-on's files, its wheels under ``wheels/`` and
its manifest with ``wheels`` and ``platforms`` filled in for what was staged.

Run by ``scripts/build-blender-extension.sh`` with the bpy venv's Python (3.11: ``tomllib``). It refuses
what would make a broken archive: a manifest whose version is not cgaskin's, a NumPy wheel (Blender
bundles NumPy 1.26; a second one breaks Blender), or a platform without its own cgaskin, numba and
llvmlite wheels (judged by Blender's builder's own rule, imported from ``--builder``)."""
from __future__ import annotations

import argparse
import importlib.util
import re
import shutil
import tomllib
from pathlib import Path

MANIFEST = "blender_manifest.toml"
#: the distributions each platform's archive needs a wheel of (their machine code is per platform)
PER_PLATFORM = ("cgaskin", "numba", "llvmlite")
#: never bundled: Blender's own
FORBIDDEN = ("numpy",)


def distribution(wheel: Path) -> str:
    """A wheel's normalised distribution name (``typing_extensions-4.16.0-...whl`` -> ``typing-extensions``)."""
    return wheel.name.split("-")[0].lower().replace("_", "-")


def toml_array(key: str, values: list) -> str:
    """``key = [...]``, one quoted value a line."""
    return f"{key} = [\n" + "".join(f'    "{value}",\n' for value in values) + "]"


def with_array(text: str, key: str, values: list) -> str:
    """The manifest's text with its top-level ``key = [...]`` (one line or several) replaced: the text is
    edited, not rewritten, so that its comments stay."""
    pattern = re.compile(rf"^{key}\s*=\s*\[.*?\]", re.MULTILINE | re.DOTALL)
    if len(pattern.findall(text)) != 1:
        raise SystemExit(f"stage: {MANIFEST} must hold one top-level `{key} = [...]`")
    return pattern.sub(lambda _: toml_array(key, values), text)


def load_builder(path: Path):
    """Blender's ``blender_ext.py`` as a module (its platform rules for wheels)."""
    spec = importlib.util.spec_from_file_location("blender_ext", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def check(wheels: list, platforms: list, builder) -> None:
    """Refuse NumPy, and a platform that lacks a wheel of one of ``PER_PLATFORM``."""
    bundled = [w.name for w in wheels if distribution(w) in FORBIDDEN]
    if bundled:
        raise SystemExit(f"stage: {bundled} must not be bundled (Blender bundles NumPy; a second one breaks it)")
    for platform in platforms:
        fits = {distribution(w) for w in wheels
                if builder.blender_platform_compatible_with_wheel_platform_from_filepath(platform, w.name)}
        missing = [name for name in PER_PLATFORM if name not in fits]
        if missing:
            raise SystemExit(f"stage: no wheel of {', '.join(missing)} for {platform} (cgaskin's: --cgaskin-wheel)")


def stage(addon: Path, target: Path, version: str, platforms: list, wheels: list, builder) -> None:
    """Write the staged extension into ``target`` (replaced)."""
    text = (addon / MANIFEST).read_text(encoding="utf-8")
    declared = tomllib.loads(text)["version"]
    if declared != version:
        raise SystemExit(f"stage: {addon / MANIFEST} says version {declared}, cgaskin is {version}")
    wheels = sorted({w.resolve() for w in wheels}, key=lambda w: w.name)
    check(wheels, platforms, builder)
    if target.exists():
        shutil.rmtree(target)
    shutil.copytree(addon, target, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", MANIFEST))
    (target / "wheels").mkdir()
    for wheel in wheels:
        shutil.copy2(wheel, target / "wheels" / wheel.name)
    text = with_array(text, "wheels", [f"./wheels/{w.name}" for w in wheels])
    text = with_array(text, "platforms", platforms)
    (target / MANIFEST).write_text(text, encoding="utf-8")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--addon", type=Path, required=True, help="the add-on's folder (blender/cgaskin_blender)")
    parser.add_argument("--stage", type=Path, required=True, help="the folder to stage into (replaced)")
    parser.add_argument("--version", required=True, help="cgaskin's version: the manifest must say the same")
    parser.add_argument("--platforms", required=True, help="Blender platforms, comma-separated (linux-x64)")
    parser.add_argument("--builder", type=Path, required=True, help="Blender's bl_pkg/cli/blender_ext.py")
    parser.add_argument("--wheels", type=Path, nargs="+", required=True)
    args = parser.parse_args()
    stage(args.addon, args.stage, args.version, args.platforms.split(","), args.wheels, load_builder(args.builder))


if __name__ == "__main__":
    main()
