"""generated/ is exactly what codegen/ emits, builds fast, and its numba cache works."""
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cgaskin.codegen import build

REPO = Path(__file__).resolve().parents[2]


def test_generated_is_fresh():
    messages = []
    stale = build.build(check=True, log=messages.append)
    assert stale == 0, "\n".join(messages)


def test_check_names_a_stale_file(tmp_path):
    for name, text in build.render().items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    kernels = tmp_path / "kernels.py"
    kernels.write_text(kernels.read_text(encoding="utf-8").replace("v_s * v_s", "v_s * v_s * 1.0", 1),
                       encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 1
    assert "generated/kernels.py" in messages[0]


def test_check_ignores_only_the_sympy_version(tmp_path, monkeypatch):
    # generated/ as another sympy release would write it, with the same kernels
    with monkeypatch.context() as m:
        m.setattr(build.sympy, "__version__", "0.0.0-other")
        files = build.render()
    assert "sympy: 0.0.0-other" in files["kernels.py"]
    for name, text in files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 0, "\n".join(messages)

    # any other difference is still stale: the header's spec hash, and a kernel line
    kernels = tmp_path / "kernels.py"
    text = kernels.read_text(encoding="utf-8")
    spec_line = next(line for line in text.splitlines() if line.startswith("spec hash: "))
    kernels.write_text(text.replace(spec_line, "spec hash: 0000000000000000", 1), encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 1
    assert "generated/kernels.py" in messages[0]
    kernels.write_text(text.replace("v_s * v_s", "v_s * v_s * 1.0", 1), encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 1
    assert "generated/kernels.py" in messages[0]
    # a file that lost its sympy line differs too
    layout = tmp_path / "layout.py"
    layout.write_text("".join(line for line in files["layout.py"].splitlines(keepends=True)
                              if not line.startswith("sympy:")), encoding="utf-8")
    kernels.write_text(text, encoding="utf-8")
    messages = []
    assert build.build(check=True, directory=tmp_path, log=messages.append) == 1
    assert "generated/layout.py" in messages[0]


def test_cli_check_exit_code():
    done = subprocess.run([sys.executable, "-m", "cgaskin.app.cli", "build", "--check"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


# A locale whose preferred encoding is ASCII: no C.UTF-8 coercion, no UTF-8 mode. Generated files hold
# ∞, − and Σ, so reading or writing them in the locale's encoding fails here.
ASCII_LOCALE = {"LC_ALL": "C", "LANG": "C", "PYTHONUTF8": "0", "PYTHONCOERCECLOCALE": "0"}


def test_build_under_an_ascii_locale(tmp_path):
    env = {**os.environ, **ASCII_LOCALE}
    probe = "import codecs, locale; print(codecs.lookup(locale.getpreferredencoding(False)).name)"
    encoding = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True)
    assert encoding.stdout.strip() == "ascii", encoding.stdout + encoding.stderr   # else this test proves nothing
    done = subprocess.run([sys.executable, "-m", "cgaskin.app.cli", "build", "--check"], env=env,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    write = f"from cgaskin.codegen import build; build.build(directory=__import__('pathlib').Path({str(tmp_path)!r}))"
    done = subprocess.run([sys.executable, "-c", write], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    for name, text in build.render().items():
        assert (tmp_path / name).read_bytes() == text.encode("utf-8"), name


def test_build_is_fast():
    start = time.perf_counter()
    build.render()
    assert time.perf_counter() - start < 30.0


def test_headers_stamp_hashes():
    files = build.render()
    assert "spec hash:" in files["kernels.py"] and "sympy:" in files["kernels.py"]
    # skinning.py imports kernels.py: its header must carry the hash of kernels.py, so that a change of
    # a callee changes the caller's text and numba's file-keyed cache recompiles it
    assert "imports kernels (hash" in files["skinning.py"]


def test_runtime_does_not_import_sympy():
    code = "import sys, cgaskin, cgaskin.versor; sys.exit('sympy' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


CACHE_PROBE = """
import warnings, sys
warnings.simplefilter('error')          # a numba cache warning (uncachable function) is a failure
import numpy as np
import cgaskin
from cgaskin import versor
from cgaskin.generated import kernels, skinning
v = versor.compose(versor.motor([0, 0, 1], 0.5, [1, 2, 3]), versor.dilator(2.0))
versor.apply(v, np.ones((4, 3)))
cgaskin.skin_vertices(np.ones((4, 3)), np.zeros((4, 1), int), np.ones((4, 1)), v[None])
misses = {name: d.stats.cache_misses for name in ('versor_to_affine_batch', 'affine_point_batch')
          for d in [getattr(kernels, name)]}
misses['skin_blend'] = skinning.skin_blend.stats.cache_misses
print(misses)
sys.exit(1 if any(misses.values()) else 0)
"""


@pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="no numba cache without the JIT")
def test_numba_cache_is_used():
    # first run fills the cache (if needed), second must load everything from it
    subprocess.run([sys.executable, "-c", CACHE_PROBE], capture_output=True, text=True)
    done = subprocess.run([sys.executable, "-c", CACHE_PROBE], capture_output=True, text=True)
    assert done.returncode == 0, f"numba recompiled on a warm cache: {done.stdout}{done.stderr}"
