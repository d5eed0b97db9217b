"""numpydoc's validation of every docstring the reference shows, as build warnings (errors under ``-W``).

Which checks apply depends on what is documented (``CHECKS``): every function, class, exception and
warning documents its parameters and return value and shows an example; a method or property documents
its parameters and return value. ``CGASKIN_DOCS_VALIDATE=0`` turns the checks off (to work on the rest
of the site while docstrings are pending); every failure found is also written, one line per object
and check, to ``docstring-validation.txt`` beside the output folder (``docs/_build/``), and
``CGASKIN_DOCS_VALIDATION_REPORT=PATH`` copies that list to ``PATH``.
"""
from __future__ import annotations

import logging as _logging
import os
from pathlib import Path

from sphinx.util import logging

logger = logging.getLogger(__name__)

#: reST problems docutils found in docstrings (object -> [("RST", message)]), in this process
RST_PROBLEMS: dict[str, list[tuple[str, str]]] = {}

#: numpydoc codes: GL08 no docstring; PR01 a parameter not documented; PR02 an unknown parameter
#: documented; PR03 parameters out of order; PR04 a parameter without a type; PR07 a parameter without
#: a description; RT01 no Returns section where the function returns something; YD01 no Yields section
#: for a generator; EX01 no Examples section
DOCUMENTED = {"GL08", "PR01", "PR02", "PR03", "PR04", "PR07", "RT01", "YD01"}
CHECKS = {
    "function": DOCUMENTED | {"EX01"},
    "class": DOCUMENTED | {"EX01"},
    "exception": {"GL08", "EX01"},
    "method": DOCUMENTED,
    "property": {"GL08"},
}


def enabled() -> bool:
    return os.environ.get("CGASKIN_DOCS_VALIDATE", "1").strip().lower() not in ("0", "false", "no", "off")


def failures(name: str, what: str) -> list[tuple[str, str]]:
    """(code, message) of each check of ``CHECKS[what]`` that the docstring of ``name`` (an import
    path such as ``cgaskin.Rig.pose``) fails."""
    from numpydoc.validate import Validator, validate
    checks = CHECKS.get(what)
    if not checks:
        return []
    try:
        errors = validate(name)["errors"]
    except StopIteration:
        # numpydoc looks for the ``def`` line of the object's source: ``property(lambda ...)`` has none
        obj = Validator._load_obj(name)
        errors = [] if getattr(obj, "__doc__", None) else [("GL08", "The object does not have a docstring")]
    return [(code, message) for code, message in errors if code in checks]


class _Collected:
    """The failures found in one build (parallel reads merge theirs into the main process's)."""

    def __init__(self):
        self.rows: dict[str, list[tuple[str, str]]] = {}


def _process_docstring(app, what, name, obj, options, lines):
    if not enabled() or what not in CHECKS:
        return
    if what == "method" and name.rsplit(".", 1)[-1].startswith("_"):
        return
    found = failures(name, what)
    if not found:
        return
    env = app.env
    rows = getattr(env, "cgaskin_docstring_failures", None)
    if rows is None:
        rows = env.cgaskin_docstring_failures = {}
    rows[name] = (env.docname, found)
    for code, message in found:
        logger.warning(f"{name}: {code} {message}", type="cgaskin", subtype="docstring",
                       location=env.docname)


def _purge(app, env, docname):
    rows = getattr(env, "cgaskin_docstring_failures", {})
    for name in [n for n, (doc, _) in rows.items() if doc == docname]:
        del rows[name]


def _merge(app, env, docnames, other):
    mine = getattr(env, "cgaskin_docstring_failures", None)
    if mine is None:
        mine = env.cgaskin_docstring_failures = {}
    mine.update(getattr(other, "cgaskin_docstring_failures", {}))


class _DocstringProblems(_logging.Filter):
    """Docutils' warnings about a docstring's reST (``docstring of NAME``) belong with the docstrings'
    work: listed in the report, and dropped with the validation when it is off."""

    def filter(self, record):
        location = getattr(record, "location", None)
        text = str(location[0] if isinstance(location, tuple) else location or "")
        line = record.__dict__.get("line") or (location[1] if isinstance(location, tuple) else None)
        if "docstring of " in text:
            name, _, rest = text.split("docstring of ", 1)[1].partition(":")
            line = line or rest.split(":", 1)[0]
        elif "<autosummary>" in text:             # a docstring's first line, in a summary table
            name = f"(the summary line of an object listed at {Path(text.split(':<autosummary>')[0]).name})"
        else:
            return True
        row = ("RST", (f"docstring line {line}: " if line else "") + record.getMessage())
        found = RST_PROBLEMS.setdefault(name, [])
        if row not in found:
            found.append(row)
        return enabled()


def report_text(rows: dict[str, tuple[str, list[tuple[str, str]]]]) -> str:
    """One line per failing object and check, after a header naming the checks."""
    rows = {name: list(found) for name, (_, found) in rows.items()}
    for name, found in RST_PROBLEMS.items():
        rows.setdefault(name, []).extend(found)
    lines = [f"# numpydoc validation of cgaskin's reference: {len(rows)} objects fail "
             f"({sum(len(v) for v in rows.values())} checks)",
             "# checks: " + "; ".join(f"{what}: {' '.join(sorted(codes))}" for what, codes in CHECKS.items())
             + "; RST: docutils' warnings about a docstring's reStructuredText",
             "# object<TAB>code<TAB>message"]
    for name in sorted(rows):
        lines += [f"{name}\t{code}\t{message}" for code, message in rows[name]]
    return "\n".join(lines) + "\n"


def _build_finished(app, exception):
    if not enabled() or exception is not None:
        return
    rows = getattr(app.env, "cgaskin_docstring_failures", {})
    text = report_text(rows)
    Path(app.outdir).parent.joinpath("docstring-validation.txt").write_text(text, encoding="utf-8")
    copy = os.environ.get("CGASKIN_DOCS_VALIDATION_REPORT")
    if copy:
        Path(copy).write_text(text, encoding="utf-8")


def setup(app):
    # first among the warning handler's filters: before Sphinx counts the warning
    for handler in _logging.getLogger("sphinx").handlers:
        if isinstance(handler, logging.WarningStreamHandler):
            handler.filters.insert(0, _DocstringProblems())
    app.connect("autodoc-process-docstring", _process_docstring)
    app.connect("env-purge-doc", _purge)
    app.connect("env-merge-info", _merge)
    app.connect("build-finished", _build_finished)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
