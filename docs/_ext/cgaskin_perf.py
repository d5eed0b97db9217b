"""``.. benchmark-table:: performance/NAME.txt``: a table a benchmark script wrote, shown as it is.

The performance page types no number: each table is a text file that a script of ``benchmarks/``
writes (the command, the machine, the commit, then the table), committed under ``docs/performance/``
and included here. The build never runs a benchmark. A file not written yet shows the command that
writes it instead (``:command:``).
"""
from __future__ import annotations

from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util.docutils import SphinxDirective


class BenchmarkTable(SphinxDirective):
    required_arguments = 1
    option_spec = {"command": directives.unchanged_required}

    def run(self):
        relative = self.arguments[0]
        path = Path(self.env.srcdir) / relative
        command = self.options.get("command", "")
        self.env.note_dependency(str(path))
        result = []
        if path.is_file():
            text = path.read_text(encoding="utf-8").rstrip("\n")
            block = nodes.literal_block(text, text)
            block["language"] = "text"
            result.append(block)
        else:
            para = nodes.paragraph()
            para += nodes.emphasis(text=f"{relative} is not written yet: ")
            para += nodes.Text("the command below writes it (from the repository root; then commit it).")
            result.append(nodes.note("", para))
        if command:
            made = nodes.paragraph()
            # the file's own first line names the command that wrote it (a long benchmark may have
            # been run with smaller arguments); this one is the default run, to write it again
            made += nodes.Text("Rewritten by " if path.is_file() else "Written by ")
            made += nodes.literal(text=command)
            result.append(made)
        return result


def setup(app):
    app.add_directive("benchmark-table", BenchmarkTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
