"""Shared fixtures: the real-model folder and the hypothesis profiles."""
import os
from pathlib import Path

import pytest
from hypothesis import settings

# `ci` is the default: the same 50 examples per property on every run (a CI verdict must not depend on
# the draw); HYPOTHESIS_PROFILE=thorough explores: >= 2000 fresh random examples per property
settings.register_profile("ci", max_examples=50, deadline=None, derandomize=True)
settings.register_profile("thorough", max_examples=2000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO = Path(__file__).resolve().parent.parent


def pytest_sessionstart(session):
    """Compile the runtime's kernels on every core before the tests call them (on a cold numba cache
    this saves the suite a good part of its compile time on a 2-core machine; warm, it only loads)."""
    from cgaskin.app.precompile import precompile
    precompile()


@pytest.fixture(scope="session")
def models_dir() -> Path:
    """The real models (env CGASKIN_MODELS, default <repo>/../shared/models); skip if absent."""
    path = Path(os.environ.get("CGASKIN_MODELS", REPO.parent / "shared" / "models"))
    if not path.is_dir():
        pytest.skip(f"real models folder {path} is absent: set CGASKIN_MODELS to the folder "
                    f"holding Arm5.glb, Fox.glb, ... (see design.md section 6)")
    return path
