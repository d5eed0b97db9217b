"""Tests that need a tool outside pip (a compiler, a browser, Mesa, Blender): skip with the reason, or
fail under CGASKIN_CI=1 (set by .ci/run), where nothing may be skipped silently."""
import os

import pytest

INSTALL = "bash scripts/install-test-deps.sh"


def require(missing, what: str) -> None:
    """Skip (fail under CGASKIN_CI=1) when ``missing`` names anything: a list of what is absent, or one
    text saying why; nothing (an empty list, None) lets the test run."""
    if not missing:
        return
    why = ", ".join(missing) if isinstance(missing, (list, tuple)) else str(missing)
    reason = f"{what} needs {why}: run `{INSTALL}`"
    if os.environ.get("CGASKIN_CI") == "1":
        pytest.fail(f"CGASKIN_CI=1: {reason}", pytrace=False)
    pytest.skip(reason)
