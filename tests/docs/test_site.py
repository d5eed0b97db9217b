"""The built site, as a reader's browser shows it: headless Chromium opens the index, a reference page,
a gallery page and the algebra page (MathJax) from ``file://``; none makes a request outside the site
(no CDN, no fonts, no analytics), logs an error or misses a file, and each shows (a screenshot).

Needs the site (``bash scripts/build-docs.sh``, or ``CGASKIN_DOCS_HTML=DIR``) and the browser that
tests/clients drive (``bash scripts/install-test-deps.sh``); skips without them (fails under
CGASKIN_CI=1: CI builds the site first)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

from tests.helpers.requirements import require

from .blocks import DOCS, REPO

PAGES = ("index.html", "api/generated/cgaskin.cut.html", "auto_examples/plot_05_drill.html", "guide/algebra.html")


def test_the_site_makes_no_request_outside_itself(tmp_path):
    site = Path(os.environ.get("CGASKIN_DOCS_HTML", DOCS / "_build" / "html"))
    chromium = os.environ.get("CGASKIN_CHROMIUM", "/usr/bin/chromium")
    puppeteer = REPO / "tests" / "clients" / "js" / "node_modules" / "puppeteer-core" / "package.json"
    missing = [what for what, there in ((f"the built site {site} (bash scripts/build-docs.sh)",
                                         all((site / page).is_file() for page in PAGES)),
                                        ("node", shutil.which("node")), (chromium, Path(chromium).is_file()),
                                        ("puppeteer-core (bash scripts/install-test-deps.sh)", puppeteer.is_file()))
               if not there]
    require(missing, "the built site's browser test")
    done = subprocess.run(["node", str(Path(__file__).with_name("site_pages.mjs")), str(site), str(tmp_path), *PAGES],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    for page in PAGES:
        seen = report[page]
        assert not seen["outside"], f"{page} asked for {seen['outside']}"
        assert not seen["errors"] and not seen["failed"], f"{page}: {seen['errors']} {seen['failed']}"
        assert "cgaskin" in seen["title"]
        shot = tmp_path / (page.replace("/", "_").replace(".html", ".png"))
        assert shot.stat().st_size > 10_000, f"{page}: the screenshot is blank"
