"""Every example of the gallery (docs/examples/*.py) runs as a script and makes what its page shows:
a picture (a PNG its scraper moves into the site) or a page (the viewer's HTML)."""
from __future__ import annotations

import runpy

import pytest

from .blocks import DOCS, sandbox

EXAMPLES = sorted((DOCS / "examples").glob("*.py"))


def test_the_gallery_has_its_examples():
    names = {p.stem for p in EXAMPLES}
    assert len(names) >= 9
    assert all(name.startswith("plot_") for name in names)       # sphinx-gallery runs them: filename_pattern


@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_an_example_runs_and_makes_its_picture(example, tmp_path):
    with sandbox(tmp_path):
        runpy.run_path(str(example), run_name="__main__")
    made = sorted(p.name for p in tmp_path.iterdir() if p.suffix in (".png", ".html"))
    assert made, f"{example.name} wrote no picture (.png) and no page (.html) in its folder"
