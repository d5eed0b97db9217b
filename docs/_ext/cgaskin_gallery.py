"""The gallery's scraper for files an example writes: PNG pictures and HTML pages.

The examples draw with cgaskin's own picture helper (``cgaskin.app.render.render_strip``, what
``cgaskin demo`` draws with), which saves a PNG and closes its figure, and save viewer pages with
``View.save``. sphinx-gallery runs an example in its own folder; after each code block this scraper
moves the PNG files that appeared there into the gallery's images (and shows them under the block),
and the HTML files into ``docs/_pages/viewer/`` (copied into the site as ``viewer/NAME``, by
``html_extra_path``) with a link under the block.
"""
from __future__ import annotations

import shutil
from pathlib import Path


class GalleryFiles:
    """An sphinx-gallery image scraper (``sphinx_gallery_conf["image_scrapers"]``)."""

    #: where the pages go before Sphinx copies them into the site (it must exist when Sphinx starts)
    PAGES = Path(__file__).resolve().parent.parent / "_pages"
    #: the pages' folder in the site
    SITE_FOLDER = "viewer"

    def __init__(self):
        (self.PAGES / self.SITE_FOLDER).mkdir(parents=True, exist_ok=True)

    def __repr__(self):                      # a stable repr: Sphinx compares configs by it
        return "GalleryFiles()"

    def __call__(self, block, block_vars, gallery_conf) -> str:
        from sphinx_gallery.scrapers import figure_rst
        folder = Path(block_vars["src_file"]).parent
        rst = []
        pictures = []
        for png in sorted(folder.glob("*.png")):
            target = block_vars["image_path_iterator"].next()
            shutil.move(png, target)
            pictures.append(target)
        if pictures:
            rst.append(figure_rst(pictures, gallery_conf["src_dir"]))
        for page in sorted(folder.glob("*.html")):
            shutil.move(page, self.PAGES / self.SITE_FOLDER / page.name)
            rst.append(f"\n`Open {page.name} <../{self.SITE_FOLDER}/{page.name}>`__ (the page the example "
                       f"saved, in this site)\n")
        return "\n".join(rst)
