"""Real clients (three.js in headless Chromium, Blender as a module): what they need, and the files
they open. A missing client skips with the command that installs it; under CGASKIN_CI=1 it fails,
so that CI never passes without having opened the files."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers.requirements import require

from .files import write_files

JS = Path(__file__).resolve().parent / "js"
CHROMIUM = os.environ.get("CGASKIN_CHROMIUM", "/usr/bin/chromium")
#: one line per client test run: what was compared (printed at the end of the session)
SUMMARY: list = []


def pytest_terminal_summary(terminalreporter):
    if SUMMARY:
        terminalreporter.section("real clients")
        for line in SUMMARY:
            terminalreporter.write_line(line)


@pytest.fixture(scope="session")
def threejs() -> dict:
    """Paths for tests/clients/js/skin_positions.mjs: node and the Chromium binary."""
    node = shutil.which("node")
    missing = [name for name, ok in (("node", node), (CHROMIUM, Path(CHROMIUM).is_file()),
                                     ("npm packages three and puppeteer-core in tests/clients/js/node_modules",
                                      all((JS / "node_modules" / p / "package.json").is_file()
                                          for p in ("three", "puppeteer-core")))) if not ok]
    require(missing, "the three.js test")
    return {"node": node, "chromium": CHROMIUM, "js": JS}


@pytest.fixture(scope="session")
def blender() -> str:
    """The Python that imports bpy (Blender 5.0 as a module: Python 3.11 only), in the virtual environment
    that scripts/install-test-deps.sh makes for it (bpy requires NumPy < 2, cgaskin's batch extra >= 2)."""
    if sys.version_info[:2] != (3, 11):
        require([f"Python 3.11 (bpy 5.0.1 has no wheel for {sys.version.split()[0]})"], "the Blender test")
    venv = Path(os.environ.get("CGASKIN_BLENDER_VENV", Path.home() / ".cache" / "cgaskin" / "bpy-5.0.1"))
    python = venv / "bin" / "python"
    found = python.is_file() and subprocess.run(
        [str(python), "-c", "import importlib.util, sys; sys.exit(importlib.util.find_spec('bpy') is None)"],
        capture_output=True).returncode == 0
    require([] if found else [f"bpy 5.0.1 in {venv} (bash scripts/install-test-deps.sh)"], "the Blender test")
    return str(python)


@pytest.fixture(scope="session")
def client_files(models_dir, tmp_path_factory) -> dict:
    """name -> path of every file in ``files.NAMES``, written once per session by the CLI."""
    return write_files(models_dir, tmp_path_factory.mktemp("client_files"))
