"""The one build pipeline of a kernel catalogue, the built-in one (``codegen.build``, into generated/) and
a user's (``codegen.catalogue_build``): compiled kernels (``codegen.trace.Compiled``) become

* the numba module: a stamped header (``codegen.headers``), then per kernel its scalar form, its hoisted
  stages and its row loop ``name_batch``, then ``KERNEL_NAMES``;
* the other targets' files (``codegen.targets``), stamped by the same command plus ``--target``;
* the op-count report (``--report``);

and ``sync`` writes the files, or (``--check``) compares them with what is on disk, ignoring only the
sympy version, and names each stale kernel of the numba module. The front ends only choose what goes in
(the ``Catalogue``), which targets, where the files go, and what to log.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from . import headers, opcount, printer
from .ir import Kernel
from .trace import Compiled

IMPORTS = "import math\n\nimport numpy as np\nfrom numba import njit\n"


@dataclass(frozen=True)
class Catalogue:
    """What a build prints, and how its files are stamped and named."""

    compiled: tuple                   # Compiled, in module order
    label: str                        # names the catalogue in messages ("codegen/", "mykernels.py")
    command: str                      # the command that writes its files, stamped in their headers
    title: str                        # the first line of the numba module's docstring
    prefix: str                       # the other targets' name prefix ("cgaskin", the file stem)
    algebra: str = headers.ALGEBRA    # the stamp's ``algebra:`` line
    documented: bool = False          # scalar kernels get ``documented``'s docstring (types, op counts)
    source: str | None = None         # where the specs are, named in the numba module's stamp
    skinning: bool = False            # the other targets also emit the skinning loop
    decorator: str = printer.NUMBA_DECORATOR     # of the numba module's kernels


def spec_hash(kernels) -> str:
    return headers.digest("\n".join(k.spec_text for k in kernels))


# -- the numba module -------------------------------------------------------------------------------
def _shape(typ, batch: bool) -> str:
    if typ.kind == "scalar":
        return "(N,)" if batch else "float"
    return f"(N, {typ.size})" if batch else f"({typ.size},)"


def documented(c: Compiled, source: str) -> Kernel:
    """The scalar kernel with its docstring: the user's text, types, shapes and op counts."""
    params, ret = c.spec.signature()
    lines = [c.spec.doc or f"Kernel ``{c.name}`` of {source}.", ""]
    lines += [f"{name} : {_shape(typ, False)}  {typ.describe()}" for name, typ in params]
    lines.append(f"returns : {'float' if c.out_size == 1 else f'tuple of {c.out_size} floats'}  {ret.describe()}")
    if c.dropped:
        lines.append(f"Dropped from the result: {', '.join(c.dropped)} (zero whenever the versor inputs are versors).")
    lines.append(f"Operations after CSE: {opcount.describe(opcount.op_counts(c.kernel))}.")
    if c.stages:
        lines.append(f"Batch form per row: {opcount.describe(opcount.op_counts(c.stages[1]))}; once per call: "
                     f"{opcount.describe(opcount.op_counts(c.stages[0]))} ({len(c.stages[0].outputs)} hoisted values).")
    doc = "\n".join(("    " + ln if ln and i else ln) for i, ln in enumerate(lines))
    doc = doc.replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    return replace(c.kernel, doc=doc)


def batch(c: Compiled, decorator: str) -> str:
    """``name_batch``: uniform inputs once, the others per row; hoisted stages when there are some."""
    if not c.uniform:
        return printer.print_batch(c.kernel, decorator)
    params, _ = c.spec.signature()
    names = [n for n, _ in params]
    shapes = ", ".join(f"{n} {_shape(t, n not in c.uniform)}" for n, t in params)
    what = (f"hoisted: ``_{c.name}_uniform`` once, then ``_{c.name}_row`` per row" if c.stages else
            "passed once; nothing is hoisted (it would not save work per row): the scalar kernel per row")
    lines = [decorator,
             f"def {c.name}_batch({', '.join(names)}, out):",
             f'    """``{c.name}`` on every row: {shapes}; out (N, {c.out_size}).',
             "",
             f"    Uniform: {', '.join(c.uniform)}; {what}.",
             '    """']
    if c.stages:
        lines.append(f"    hoisted = _{c.name}_uniform({', '.join(n for n in names if n in c.uniform)})")
        call = f"_{c.name}_row(hoisted, {', '.join(f'{n}[row]' for n in names if n not in c.uniform)})"
    else:
        call = f"{c.name}({', '.join(n if n in c.uniform else f'{n}[row]' for n in names)})"
    lines.append("    for row in range(out.shape[0]):")
    lines += printer.store_rows(call, c.out_size)
    return "\n".join(lines) + "\n"


def numba_module(cat: Catalogue) -> tuple[str, dict[str, str]]:
    """(module text, {kernel name: its block of the text}): the block is what ``sync`` looks for to
    name a stale kernel."""
    chunks = {}
    for c in cat.compiled:
        parts = [printer.print_kernel(documented(c, cat.label) if cat.documented else c.kernel, cat.decorator)]
        parts += [printer.print_kernel(s, cat.decorator) for s in c.stages or ()]
        parts.append(batch(c, cat.decorator))
        chunks[c.name] = "\n\n".join(parts)
    kernels = [c.kernel for c in cat.compiled] + [s for c in cat.compiled for s in c.stages or ()]
    names = ", ".join(repr(c.name) for c in cat.compiled)
    body = "\n\n".join([IMPORTS, *chunks.values(), f"KERNEL_NAMES = ({names},)\n"])
    stamp = headers.stamp(cat.command, spec_hash(kernels), cat.algebra, source=cat.source)
    return headers.python_header(cat.title, stamp) + "\n" + body, chunks


# -- the other targets, the report --------------------------------------------------------------------
def target_files(cat: Catalogue, target: str) -> dict[str, str]:
    """{file name: text} of one target other than numba (``codegen.targets.render``)."""
    from . import targets as printers
    kernels = [c.kernel for c in cat.compiled]
    stamp = headers.stamp(f"{cat.command} --target {target}", spec_hash(kernels), cat.algebra)
    uniform = {c.name: c.uniform for c in cat.compiled if c.uniform}
    return printers.render(target, kernels, prefix=cat.prefix, header=stamp, uniform=uniform, skinning=cat.skinning)


def report_table(cat: Catalogue) -> str:
    """The op-count table (``--report``): each scalar form, and for a hoisted batch form its per-row and
    once-per-call parts."""
    rows = []
    for c in cat.compiled:
        rows.append((c.name, opcount.op_counts(c.kernel), "scalar form"))
        if c.stages:
            rows.append(("  per row", opcount.op_counts(c.stages[1]), "batch form, hoisted"))
            rows.append(("  per call", opcount.op_counts(c.stages[0]), f"{len(c.stages[0].outputs)} hoisted values"))
    return opcount.table(rows)


# -- writing and checking -----------------------------------------------------------------------------
@dataclass
class Synced:
    stale: int                        # stale kernels and files (a stale numba module: its stale kernels, ≥ 1)
    written: list                     # the paths written
    messages: list                    # one line per stale kernel or file (a check)


def sync(files: dict[Path, str], check: bool, label: str, hint: str, chunks: dict[Path, dict] | None = None,
         shown=str) -> Synced:
    """Write ``files`` {path: text} where they differ from disk, or (``check``) compare them; a file
    that differs only in its header's sympy version is rewritten by a build and fresh for a check.
    ``chunks`` {path: {kernel name: block}} names the stale kernels of a numba module; ``label`` the
    catalogue and ``hint`` the command to run, in the messages; ``shown(path)`` how they name a file."""
    result = Synced(0, [], [])
    for path, wanted in files.items():
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if current == wanted:
            continue
        if not check:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(wanted, encoding="utf-8")
            result.written.append(path)
        elif current is None:
            result.messages.append(f"stale: {shown(path)} does not exist; {hint}")
            result.stale += 1
        elif headers.without_sympy_version(current) == headers.without_sympy_version(wanted):
            continue
        elif path in (chunks or {}):
            names = [name for name, chunk in chunks[path].items() if chunk not in current]
            result.messages += [f"stale: {shown(path)}: kernel {name!r} differs from what {label} emits; {hint}"
                                for name in names]
            if not names:
                result.messages.append(f"stale: {shown(path)}: the header or the kernel list differs from what "
                                       f"{label} emits; {hint}")
            result.stale += max(1, len(names))
        else:
            result.messages.append(f"stale: {shown(path)} differs from what {label} emits; {hint}")
            result.stale += 1
    return result
