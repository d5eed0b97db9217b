"""Shared fixtures: the real-model folder, the session's numba cache and the hypothesis profiles."""
import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings

# The session's numba cache: an empty folder of its own, unless NUMBA_CACHE_DIR is set (subprocesses,
# Dask workers and the CLI inherit it). The session's precompile fills it before anything else runs, and
# tests/app/test_precompile.py's completeness check (run first) works on that cache: after precompile,
# nothing compiles, without compiling every kernel a second time into another empty cache (minutes).
# numba is imported before this file (pytest resolves numba.NumbaWarning in filterwarnings): its
# configuration reads the variable again; cgaskin's kernels, imported later, find their cache there.
SESSION_CACHE = None
if "NUMBA_CACHE_DIR" not in os.environ:
    SESSION_CACHE = tempfile.mkdtemp(prefix="cgaskin-tests-numba-")
    os.environ["NUMBA_CACHE_DIR"] = SESSION_CACHE
    from numba.core import config as _numba_config
    _numba_config.reload_config()

# `ci` is the default: the same 50 examples per property on every run (a CI verdict must not depend on
# the draw); HYPOTHESIS_PROFILE=thorough explores: >= 2000 fresh random examples per property
settings.register_profile("ci", max_examples=50, deadline=None, derandomize=True)
settings.register_profile("thorough", max_examples=2000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

REPO = Path(__file__).resolve().parent.parent


def _compiled(cache) -> frozenset:
    """The compiled overloads (numba's .nbc files) in a cache folder."""
    return frozenset(str(p.relative_to(cache)) for p in Path(cache).rglob("*.nbc"))


def pytest_sessionstart(session):
    """Compile the runtime's kernels on every core before the tests call them (on a cold numba cache
    this saves the suite a good part of its compile time on a 2-core machine; warm, it only loads)."""
    from cgaskin.app.precompile import precompile
    precompile()
    session.config.cgaskin_precompiled = _compiled(SESSION_CACHE) if SESSION_CACHE else None


def pytest_collection_modifyitems(session, config, items):
    """precompile's completeness check first, while the session's cache holds only what precompile made."""
    first = [item for item in items if item.nodeid.endswith("test_precompile.py::test_after_precompile_nothing_compiles")]
    items[:] = first + [item for item in items if item not in first]


def pytest_sessionfinish(session, exitstatus):
    if SESSION_CACHE:
        import shutil
        shutil.rmtree(SESSION_CACHE, ignore_errors=True)


@pytest.fixture
def precompiled_cache(request):
    """The session's numba cache if it still holds exactly what the session's precompile made (an empty
    cache before it), else None."""
    made = getattr(request.config, "cgaskin_precompiled", None)
    return SESSION_CACHE if made is not None and _compiled(SESSION_CACHE) == made else None


@pytest.fixture(scope="session")
def models_dir() -> Path:
    """The real models (env CGASKIN_MODELS, default <repo>/../shared/models); skip if absent."""
    path = Path(os.environ.get("CGASKIN_MODELS", REPO.parent / "shared" / "models"))
    if not path.is_dir():
        pytest.skip(f"real models folder {path} is absent: set CGASKIN_MODELS to the folder "
                    f"holding Arm5.glb, Fox.glb, ... (see design.md section 6)")
    return path
