"""Shared fixtures: the real-model folder, the numba cache precompile filled, and the hypothesis profiles."""
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


def _compiled() -> frozenset:
    """The compiled overloads (numba's .nbc files) in cgaskin's numba cache: NUMBA_CACHE_DIR, else the
    __pycache__ folders beside the package's sources (numba's default)."""
    from numba.core import config
    import cgaskin
    import cgaskin.generated
    import cgaskin.rigs
    if config.CACHE_DIR:
        roots = [Path(config.CACHE_DIR)]
    else:
        roots = [Path(m.__file__).parent for m in (cgaskin, cgaskin.generated, cgaskin.rigs)]
    return frozenset(str(p) for root in roots for p in root.rglob("*.nbc"))


def pytest_sessionstart(session):
    """Compile the runtime's kernels on every core before the tests call them (on a cold numba cache
    this saves the suite a good part of its compile time on a 2-core machine; warm, it only loads).
    On a cold cache (a fresh install, CI's clean clone) the cache then holds exactly what precompile
    made: tests/app/test_precompile.py's completeness check runs first and works on it, instead of
    compiling every kernel a second time into another empty cache (minutes)."""
    from cgaskin.app.precompile import precompile
    cold = not _compiled()
    precompile()
    session.config.cgaskin_precompiled = _compiled() if cold else None


def pytest_collection_modifyitems(session, config, items):
    """precompile's completeness check first, while a cold cache holds only what precompile made."""
    first = [item for item in items if item.nodeid.endswith("test_precompile.py::test_after_precompile_nothing_compiles")]
    items[:] = first + [item for item in items if item not in first]


@pytest.fixture
def precompiled_cache(request) -> bool:
    """Whether the numba cache holds exactly what the session's precompile made from an empty cache."""
    made = getattr(request.config, "cgaskin_precompiled", None)
    return made is not None and _compiled() == made


@pytest.fixture(scope="session")
def models_dir() -> Path:
    """The real models (env CGASKIN_MODELS, default <repo>/../shared/models); skip if absent."""
    path = Path(os.environ.get("CGASKIN_MODELS", REPO.parent / "shared" / "models"))
    if not path.is_dir():
        pytest.skip(f"real models folder {path} is absent: set CGASKIN_MODELS to the folder "
                    f"holding Arm5.glb, Fox.glb, ... (see design.md section 6)")
    return path
