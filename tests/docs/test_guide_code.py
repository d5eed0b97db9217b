"""Every Python block of the guide pages and of the README runs (``tests/docs/blocks.py`` says how a
page's blocks are found, marked and run), so that the documentation's code cannot rot."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from .blocks import PYTHON, REPO, SHELL, blocks_of, guide_pages, sandbox, shell_code

PAGES = guide_pages() + [REPO / "README.md"]


def _link_models(models: Path, folder: Path) -> None:
    for model in models.iterdir():
        if model.is_file():
            (folder / model.name).symlink_to(model)


def _models_or_skip(page: Path) -> Path:
    models = Path(os.environ.get("CGASKIN_MODELS", REPO.parent / "shared" / "models"))
    if not models.is_dir():
        pytest.skip(f"{page.name}'s code reads the real models: {models} is absent (set CGASKIN_MODELS)")
    return models


def run_page(page: Path, folder: Path) -> int:
    """Run the page's blocks in order in one namespace, in ``folder``; returns how many ran."""
    blocks = [b for b in blocks_of(page) if b.mark != "skip" and (b.language in PYTHON or b.mark == "run")]
    if page.name == "README.md" or any(b.mark == "models" for b in blocks):
        _link_models(_models_or_skip(page), folder)
    namespace = {"__name__": "__guide__"}
    with sandbox(folder):
        for block in blocks:
            if block.language in SHELL:
                env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
                done = subprocess.run(["bash", "-e", "-c", shell_code(block)], cwd=folder, env=env,
                                      capture_output=True, text=True, timeout=300)
                assert done.returncode == 0, f"{block.where}: exit {done.returncode}\n{done.stdout}\n{done.stderr}"
                continue
            if block.file_name:
                target = folder / block.file_name
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_text(block.code, encoding="utf-8")
            try:
                exec(compile(block.code, block.where, "exec"), namespace)
            except Exception as error:
                raise AssertionError(f"{block.where}: the block raised {type(error).__name__}: {error}") from error
    return len(blocks)


def test_the_guide_has_pages_with_code():
    assert len(guide_pages()) >= 10
    assert sum(len(blocks_of(p)) for p in guide_pages()) >= 20


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(REPO)) for p in PAGES])
def test_the_code_of_a_page_runs(page, tmp_path):
    run_page(page, tmp_path)


def test_a_failing_block_names_its_page_and_line(tmp_path):
    page = tmp_path / "page.rst"
    page.write_text("Title\n=====\n\n.. code-block:: python\n\n   x = 1\n   assert x == 2\n")
    folder = tmp_path / "run"
    folder.mkdir()
    with pytest.raises(AssertionError, match=r"page.rst:6: the block raised AssertionError"):
        run_page(page, folder)
