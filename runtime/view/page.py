"""One self-contained HTML page that shows a rig: three.js and the viewer inlined, the rig embedded as
a .glb in base64; it opens offline from file:// (and in a notebook's iframe) without any request.

Why the modules go through blob: URLs: a browser refuses to load ES modules from file:// (each is a
cross-origin fetch from an opaque origin), and an inline ``<script type=module>`` cannot be imported by
name. So every module's text sits in a ``<script type="text/plain" data-module=NAME>`` block, and a
small classic script (``BOOTSTRAP``) makes each a blob: URL, installs an import map from the names to
those URLs and then starts the viewer's entry module. Blob URLs keep the text as it is (data: URLs
would cost a third more in base64) and import maps may be added this way as long as no module has
started loading (Chromium, Firefox 108+, Safari 16.4+). A blob: URL is no base for a relative import,
so the relative imports of three.js's files (``./three.core.js``, ``../utils/...``) are rewritten to
the bare names the import map holds; each rewrite is checked, so a three.js update that changes them
fails loudly here rather than in the browser.
"""
from __future__ import annotations

import base64
import html
import json
import posixpath
import re
from importlib import resources

from ..errors import InternalError, InvalidInputError
from .assets import THREE_FILES, THREE_VERSION, VIEWER_MODULES, asset_text

#: the page's skinning modes: "cgaskin" blends the bones' versors with the generated GLSL ES chunk in
#: the vertex shader (assets/viewer/cgaskin_skinning.js), "three" is three.js's matrix skinning
SKINNING_MODES = ("cgaskin", "three")

#: modules made of files of cgaskin.generated (built by ``cgaskin build``, never edited by hand): the
#: kernels in JavaScript, and the WebGL2 skinning chunk as a module whose default export is its text
GENERATED_MODULES = {"cgaskin/kernels.js": ("js", "cgaskin.mjs"),
                     "cgaskin/skin_webgl.js": ("glsl", "cgaskin_skin_webgl.glsl")}

#: import specifier -> the file under assets/ that it names
def _module_files() -> dict:
    files = {}
    for mine in THREE_FILES:
        if mine.endswith(".js"):
            files["three" if mine == "three.module.js" else f"three/{mine}"] = f"three/{mine}"
    for name in VIEWER_MODULES:
        files[f"cgaskin/{name}"] = f"viewer/{name}"
    return files | dict.fromkeys(GENERATED_MODULES)


MODULES = _module_files()
_RELATIVE = re.compile(r"""(\bfrom\s*|\bimport\s*)(['"])(\.{1,2}/[^'"]+)\2""")

BOOTSTRAP = """\
// cgaskin view: turn the inlined modules into blob: URLs, map their names to them, start the viewer
(() => {
    const imports = {};
    for (const script of document.querySelectorAll('script[type="text/plain"][data-module]'))
        imports[script.dataset.module] = URL.createObjectURL(
            new Blob([script.textContent], {type: 'text/javascript'}));
    const map = document.createElement('script');
    map.type = 'importmap';
    map.textContent = JSON.stringify({imports});
    document.head.appendChild(map);
    const main = document.createElement('script');
    main.type = 'module';
    main.textContent = "import 'cgaskin/main.js';";
    document.body.appendChild(main);
})();
"""


def module_text(name: str) -> str:
    """The text of the module imported as ``name``, its relative imports rewritten to bare names of
    ``MODULES`` (the only imports a blob: URL can resolve)."""
    if name in GENERATED_MODULES:
        return _generated_text(*GENERATED_MODULES[name])
    path = MODULES[name]
    text = asset_text(path)
    folder = posixpath.dirname(path)

    def bare(match):
        target = posixpath.normpath(posixpath.join(folder, match.group(3)))
        names = [key for key, value in MODULES.items() if value == target]
        if not names:
            raise InternalError(f"{path} imports {match.group(3)}, which the page does not inline "
                               f"(three {THREE_VERSION}: add it to cgaskin.view.assets.THREE_FILES)")
        return f"{match.group(1)}{match.group(2)}{names[0]}{match.group(2)}"

    return _RELATIVE.sub(bare, text)


def _generated_text(folder: str, file: str) -> str:
    """A module of a file of ``cgaskin.generated.<folder>``: an ES module as it is, other text as the
    default export of a module (a JSON string literal is a JavaScript one)."""
    text = resources.files(f"cgaskin.generated.{folder}").joinpath(file).read_text(encoding="utf-8")
    return text if file.endswith(".mjs") else f"export default {json.dumps(text)};\n"


def _script_text(text: str) -> str:
    """``text`` safe inside a <script> element: "</script" and "<!--" cannot end or disturb it.
    In JavaScript strings, templates and regular expressions "<\\/" means "</" (and in JSON too)."""
    return re.sub(r"</(script)", r"<\\/\1", text, flags=re.IGNORECASE).replace("<!--", "<\\!--")


def _json_text(value) -> str:
    """``value`` as JSON safe inside a <script> element (every "<" written as the escape \\u003c)."""
    return json.dumps(value).replace("<", "\\u003c")


def page_html(glb: bytes, *, name: str, rims, clip: str | None, play: bool = True, time: float = 0.0,
              skinning: str = "three", serve: bool = False) -> str:
    """The viewer's HTML around a model already written as glTF.

    Parameters
    ----------
    glb : bytes
        The model, a binary glTF (what ``cgaskin.save`` writes).
    name : str
        Shown in the title and the status line.
    rims : (2b,) array_like of int
        Flat vertex pairs of the boundary edges to draw (``rim_edges``).
    clip : str or None
        The clip to show first (None: the rest pose).
    play : bool, optional
        Start playing it.
    time : float, optional
        Where in it to start (seconds).
    skinning : str, optional
        One of ``SKINNING_MODES``.
    serve : bool, optional
        The page of ``cgaskin serve`` (the surgery panel, talking to the server that sent it over a
        WebSocket at its own address); False: the offline viewer.

    Returns
    -------
    str

    Examples
    --------
    >>> path = cgaskin.save(cgaskin.capsule_arm(), "arm.glb")
    >>> page = cgaskin.view.page_html(path.read_bytes(), name="arm", rims=[], clip="wave")
    >>> "<title>arm: cgaskin view</title>" in page
    True
    """
    if skinning not in SKINNING_MODES:
        raise InvalidInputError(f"skinning {skinning!r}: the page knows {', '.join(SKINNING_MODES)}")
    data = {"name": name, "clip": clip, "play": bool(play), "time": float(time), "skinning": skinning,
            "rims": [int(v) for v in rims], "three": THREE_VERSION, "serve": bool(serve)}
    blocks = [f'<script type="text/plain" data-module="{html.escape(module)}">\n{_script_text(module_text(module))}\n</script>'
              for module in MODULES]
    return "\n".join([
        "<!doctype html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        '<link rel="icon" href="data:,">',   # (no favicon request: the page makes none at all)
        f"<title>{html.escape(name)}: cgaskin {'serve' if serve else 'view'}</title>",
        f"<style>\n{asset_text('viewer/viewer.css')}</style>",
        "</head><body>",
        '<div id="cgaskin-view"><canvas></canvas></div>',
        f'<script type="application/json" id="cgaskin-data">{_json_text(data)}</script>',
        f'<script type="application/octet-stream" id="cgaskin-model">{base64.b64encode(glb).decode("ascii")}</script>',
        f"<!-- three.js {THREE_VERSION} (MIT licence below), then the cgaskin viewer's modules -->",
        f'<script type="text/plain" id="three-license">\n{_script_text(asset_text("three/LICENSE"))}</script>',
        *blocks,
        f"<script>\n{BOOTSTRAP}</script>",
        "</body></html>",
        "",
    ])
