"""The code blocks of the guide pages (``docs/**/*.rst``) and of the README, as the tests run them.

A page's blocks run in order in one namespace, in a fresh folder (so a page reads like one session):
``.. code-block:: python`` in reST, a ```` ```python ```` fence in Markdown. A Python block whose first
line is ``# NAME.py`` is also written to that file first (a catalogue the next blocks build). A
comment right above a block (blank lines between are fine) says how else to treat it:

- ``.. test: skip REASON`` (reST) / ``<!-- test: skip REASON -->`` (Markdown): not run;
- ``.. test: run``: a ``sh``/``console`` block run by bash (``$ `` prompts stripped), which must exit 0;
- ``.. test: models``: the page needs the real models: they are linked into its folder (the test
  skips when ``CGASKIN_MODELS`` is absent). The README's blocks always need them (they use Fox.glb).
"""
from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
#: what the docs build writes into docs/ (not pages of the guide)
GENERATED = ("_build", "api", "auto_examples", "_pages", "examples")

_RST_BLOCK = re.compile(r"^(?P<indent>[ \t]*)\.\. (?:code-block|code|sourcecode):: *(?P<lang>\S+)\s*$")
_RST_MARK = re.compile(r"^\s*\.\. test: *(?P<mark>\S+) *(?P<reason>.*)$")
_MD_FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w+-]*)\s*$")
_MD_MARK = re.compile(r"^\s*<!-- *test: *(?P<mark>\S+) *(?P<reason>.*?) *-->\s*$")
PYTHON = ("python", "py", "python3", "pycon")
SHELL = ("sh", "bash", "console", "shell")


@dataclass(frozen=True)
class Block:
    path: Path
    line: int              # 1-based line of the block's first code line
    language: str
    code: str
    mark: str = ""         # "", "skip", "run", "models"
    reason: str = ""

    @property
    def where(self) -> str:
        path = self.path.relative_to(REPO) if self.path.is_relative_to(REPO) else self.path
        return f"{path}:{self.line}"

    @property
    def file_name(self) -> str | None:
        """``NAME.py`` when the block's first line is the comment ``# NAME.py``."""
        first = self.code.lstrip("\n").split("\n", 1)[0].strip()
        match = re.fullmatch(r"#\s*([\w./-]+\.py)", first)
        return match.group(1) if match else None


def _mark_above(lines, index, pattern):
    """The marker comment above line ``index`` (skipping blank lines), or ("", "")."""
    j = index - 1
    while j >= 0 and not lines[j].strip():
        j -= 1
    match = pattern.match(lines[j]) if j >= 0 else None
    return (match.group("mark"), match.group("reason").strip()) if match else ("", "")


def rst_blocks(path: Path) -> list[Block]:
    lines = path.read_text(encoding="utf-8").split("\n")
    blocks = []
    i = 0
    while i < len(lines):
        match = _RST_BLOCK.match(lines[i])
        if not match:
            i += 1
            continue
        mark, reason = _mark_above(lines, i, _RST_MARK)
        indent = len(match.group("indent"))
        j = i + 1
        while j < len(lines) and re.match(r"^\s+:[\w-]+:", lines[j]):        # the directive's options
            j += 1
        body, first = [], None
        while j < len(lines):
            line = lines[j]
            if line.strip() and len(line) - len(line.lstrip()) <= indent:
                break
            if first is None and line.strip():
                first = j
            body.append(line)
            j += 1
        while body and not body[-1].strip():
            body.pop()
        code_lines = [b for b in body]
        while code_lines and not code_lines[0].strip():
            code_lines.pop(0)
        width = min((len(b) - len(b.lstrip()) for b in code_lines if b.strip()), default=0)
        code = "\n".join(b[width:] for b in code_lines) + "\n"
        blocks.append(Block(path, (first or i) + 1, match.group("lang").lower(), code, mark, reason))
        i = j
    return blocks


def markdown_blocks(path: Path) -> list[Block]:
    lines = path.read_text(encoding="utf-8").split("\n")
    blocks = []
    i = 0
    while i < len(lines):
        match = _MD_FENCE.match(lines[i])
        if not match or not match.group("lang"):
            i += 1
            continue
        mark, reason = _mark_above(lines, i, _MD_MARK)
        j = i + 1
        while j < len(lines) and not re.match(r"^\s*```\s*$", lines[j]):
            j += 1
        code = "\n".join(lines[i + 1:j]) + "\n"
        blocks.append(Block(path, i + 2, match.group("lang").lower(), code, mark, reason))
        i = j + 1
    return blocks


def guide_pages() -> list[Path]:
    """The reST and Markdown pages of docs/ that people wrote (not what the build generates)."""
    return sorted(p for pattern in ("*.rst", "*.md") for p in DOCS.rglob(pattern)
                  if p.relative_to(DOCS).parts[0] not in GENERATED)


def blocks_of(path: Path) -> list[Block]:
    return markdown_blocks(path) if path.suffix == ".md" else rst_blocks(path)


def shell_code(block: Block) -> str:
    """A shell block as bash runs it: ``$ `` prompts stripped; in a console block only prompted lines."""
    lines = block.code.split("\n")
    if any(line.startswith("$ ") for line in lines):
        return "\n".join(line[2:] for line in lines if line.startswith("$ ")) + "\n"
    return block.code


@contextlib.contextmanager
def sandbox(folder: Path):
    """Run code as a reader would, in ``folder``: the working directory and the first entry of
    ``sys.path``; afterwards the directory, ``sys.path`` and matplotlib are as before, and the modules
    imported from temporary folders (a catalogue's generated package) are forgotten, so that the next
    page's package of the same name is imported afresh."""
    path_before = list(sys.path)
    modules_before = set(sys.modules)
    cwd = os.getcwd()
    sys.path.insert(0, str(folder))
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(cwd)
        sys.path[:] = path_before
        temporary = (str(Path(tempfile.gettempdir()).resolve()), str(Path(folder).resolve()))
        for name in set(sys.modules) - modules_before:
            file = str(getattr(sys.modules[name], "__file__", "") or "")
            if file and str(Path(file).resolve()).startswith(temporary):
                del sys.modules[name]
        if "matplotlib.pyplot" in sys.modules:
            sys.modules["matplotlib.pyplot"].close("all")
