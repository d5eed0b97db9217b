"""The page's static files: three.js, vendored from the npm package (never fetched at run time), and
the viewer's own JavaScript and CSS.

three.js is copied verbatim from ``node_modules/three`` at development time by ``vendor_three``
(``python -m cgaskin.view.assets tests/clients/js/node_modules/three``, or
``scripts/vendor-three.sh``); ``tests/clients/test_view.py`` checks that the copies equal the files
of the npm version that ``tests/clients/js/package.json`` pins, so they cannot drift silently.
"""
from __future__ import annotations

import json
import shutil
import sys
from importlib import resources
from pathlib import Path

from ..errors import InvalidInputError

#: the three.js version the copies come from (tests/clients/js/package.json pins the same)
THREE_VERSION = "0.187.0"

#: vendored file (under assets/three/) -> its path in the npm package ``three``
THREE_FILES = {
    "three.core.js": "build/three.core.js",
    "three.module.js": "build/three.module.js",
    "addons/loaders/GLTFLoader.js": "examples/jsm/loaders/GLTFLoader.js",
    "addons/utils/BufferGeometryUtils.js": "examples/jsm/utils/BufferGeometryUtils.js",
    "addons/utils/SkeletonUtils.js": "examples/jsm/utils/SkeletonUtils.js",
    "addons/controls/OrbitControls.js": "examples/jsm/controls/OrbitControls.js",
    "addons/controls/TransformControls.js": "examples/jsm/controls/TransformControls.js",
    "LICENSE": "LICENSE",
}

#: the viewer's own modules (under assets/viewer/), in the order the import map lists them
VIEWER_MODULES = ("ui.js", "cgaskin_skinning.js", "scene.js", "playback.js", "weights.js", "skeleton.js", "rims.js",
                  "mesh_delta.js", "surgery.js", "main.js")


def asset_text(relative: str) -> str:
    """The text of ``assets/<relative>`` (UTF-8), read through importlib.resources so that it works
    from an installed wheel as from the checkout."""
    path = resources.files(__package__).joinpath("assets", *relative.split("/"))
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InvalidInputError(f"cgaskin's viewer asset {relative} is missing from the installation "
                                f"({path}); reinstall cgaskin") from None


def assets_folder() -> Path:
    """The assets folder in the checkout (where ``vendor_three`` writes)."""
    return Path(__file__).resolve().parent / "assets"


def vendor_three(package: str | Path, assets: str | Path | None = None) -> list[Path]:
    """Copy the three.js files of ``THREE_FILES`` from the npm package folder ``package``
    (``.../node_modules/three``) into ``assets/three/``; refuse a version other than ``THREE_VERSION``
    (change both together: the page's import rewriting is checked against that version's files).

    Returns the written paths.
    """
    package = Path(package)
    try:
        version = json.loads((package / "package.json").read_text(encoding="utf-8"))["version"]
    except (OSError, ValueError, KeyError) as exc:
        raise InvalidInputError(f"{package}: not the npm package three ({exc})") from None
    if version != THREE_VERSION:
        raise InvalidInputError(f"{package} is three {version}; cgaskin vendors {THREE_VERSION} (update "
                                f"THREE_VERSION in {__file__} and tests/clients/js/package.json together)")
    target = Path(assets) if assets is not None else assets_folder()
    written = []
    for mine, theirs in THREE_FILES.items():
        destination = target / "three" / mine
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(package / theirs, destination)
        written.append(destination)
    return written


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m cgaskin.view.assets PATH/TO/node_modules/three")
    for path in vendor_three(sys.argv[1]):
        print(f"wrote {path}")
