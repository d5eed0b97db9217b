"""The Blender tests: the extension's operators run in Blender as a Python module (bpy 5.0, headless),
in the virtual environment scripts/install-test-deps.sh makes for it (``blender`` fixture, shared
with tests/clients)."""
from tests.clients.conftest import blender  # noqa: F401  (the fixture)
