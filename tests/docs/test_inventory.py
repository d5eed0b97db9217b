"""The reference documents exactly the public API: the names in the built site's ``objects.inv`` (at
module level: each module and ``module.name``) equal every public name of the modules the reference
covers (``docs/_ext/cgaskin_api.py``: a module's ``__all__``, else its public attributes that are not
modules).

The test reads the inventory of the site ``scripts/build-docs.sh`` built (``docs/_build/html``, or
``CGASKIN_DOCS_HTML=DIR``) when that is newer than every source it documents; else it builds the
reference alone (``CGASKIN_DOCS_ONLY=api``: no guide, no gallery, a plain theme; about ten seconds)."""
from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

from .blocks import DOCS, REPO


def _api():
    spec = importlib.util.spec_from_file_location("cgaskin_api", DOCS / "_ext" / "cgaskin_api.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def read_inventory(path: Path) -> dict:
    """name -> role ("py:function", ...) of a Sphinx inventory (version 2: four header lines, then
    zlib-compressed lines "name domain:role priority uri display name")."""
    data = path.read_bytes()
    header = data.split(b"\n", 4)
    assert header[0] == b"# Sphinx inventory version 2", header[0]
    entries = {}
    for line in zlib.decompress(header[4]).decode("utf-8").splitlines():
        match = re.match(r"(.+?)\s+(\S+:\S+)\s+(-?\d+)\s+(\S*)\s+(.*)", line)
        if match:
            entries[match.group(1)] = match.group(2)
    return entries


def built_site_inventory() -> Path | None:
    """The built site's objects.inv if it is newer than every file it is made from, else None."""
    path = Path(os.environ.get("CGASKIN_DOCS_HTML", DOCS / "_build" / "html")) / "objects.inv"
    if not path.is_file():
        return None
    sources = [p for folder in ("runtime", "rigs", "codegen", "generated") for p in (REPO / folder).rglob("*.py")]
    sources += [p for p in DOCS.rglob("*") if p.suffix in (".rst", ".py", ".txt")
                and p.relative_to(DOCS).parts[0] not in ("_build", "api", "auto_examples", "_pages")]
    newest = max(p.stat().st_mtime for p in sources)
    return path if path.stat().st_mtime > newest else None


@pytest.fixture(scope="module")
def inventory(tmp_path_factory) -> dict:
    built = built_site_inventory()
    if built is not None:
        return read_inventory(built)
    out = tmp_path_factory.mktemp("docs_api")
    env = {**os.environ, "CGASKIN_DOCS_ONLY": "api"}
    done = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-q", "-d", str(out / "doctrees"),
                           str(DOCS), str(out / "html")], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    return read_inventory(out / "html" / "objects.inv")


def test_the_inventory_holds_exactly_the_public_api(inventory):
    api = _api()
    expected = api.expected_inventory()
    documented = {name for name, role in inventory.items() if role.startswith("py:")
                  and (name in api.MODULES or name.rsplit(".", 1)[0] in api.MODULES)}
    missing, extra = sorted(expected - documented), sorted(documented - expected)
    assert not missing and not extra, f"not in the reference: {missing}; in it but not public: {extra}"


def test_every_kind_of_name_is_there(inventory):
    roles = {inventory[name] for name in ("cgaskin.cut", "cgaskin.Rig", "cgaskin.errors.TearPathError",
                                          "cgaskin.errors.PlacementWarning", "cgaskin.versor.VERSOR_BLADES",
                                          "cgaskin.codegen.kernel", "cgaskin.batch.run", "cgaskin.serve.Limits")}
    assert roles == {"py:function", "py:class", "py:exception", "py:data"}
    assert inventory.get("cgaskin.Rig.pose") == "py:method"       # members are documented with their class


def test_the_public_api_is_what_the_package_exports():
    api = _api()
    import cgaskin
    names = api.public_names("cgaskin")
    assert {"load", "save", "skin", "cut", "tear", "drill", "Surgery", "Rig", "CgaskinError"} <= set(names)
    assert not {"versor", "errors", "surgery", "animation"} & set(names)        # modules have pages of their own
    assert all(not n.startswith("_") and hasattr(cgaskin, n) for n in names)
