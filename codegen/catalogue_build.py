"""Build a user's catalogue of ``@kernel`` functions (``codegen.language``) into one numba module.

    build_catalogue("mykernels.py", "mypkg/generated")          # writes mypkg/generated/mykernels.py
    build_catalogue("mykernels.py", "mypkg/generated", check=True)   # 0 when up to date
    cgaskin build --catalogue mykernels.py --out mypkg/generated [--check]

The module holds, per kernel, ``name(...)`` (the scalar form: inputs as 1-D arrays or floats, returns
a float or a tuple of floats) and ``name_batch(..., out)`` (every row: uniform inputs single, the
others (N, ...), out (N, k)); a stamped header as generated/kernels.py has; each kernel's docstring
holds its symbolic expansion and its operation counts. It imports numpy and numba only.

Uniform inputs (``@kernel(uniform=("V",))``) are hoisted: every output is written as a polynomial in
the per-row symbols whose coefficients are polynomials in the uniform ones (divided by the result's
down-projection weight when that depends on uniforms only); those coefficients are computed once per
call by ``_name_uniform`` and the row loop calls ``_name_row`` on them. For a versor sandwich on a
point this finds the 3×4 affine map that ``versor_to_affine`` stages by hand. The staging is used only
when it saves work per row (counted after CSE); otherwise the loop calls the scalar kernel with the
uniform inputs passed once (their unpacking is then left to numba/LLVM, nothing is hoisted).
"""
from __future__ import annotations

import glob
import hashlib
import importlib
import importlib.util
import re
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import sympy

from . import algebras, headers, hoist, opcount, printer
from .ir import CodegenError, Kernel, KernelBuilder, as_expr
from .language import KernelSpec
from .values import as_value, building

RESERVED = {"out", "row", "r", "hoisted", "math", "np", "njit"}


@dataclass(frozen=True)
class Compiled:
    spec: KernelSpec
    kernel: Kernel                    # the scalar form
    stages: tuple | None              # (uniform Kernel, row Kernel) when the batch form is hoisted
    uniform: tuple                    # names of the uniform inputs
    out_size: int
    dropped: tuple = ()               # blades dropped as zero for versor inputs (_versor_pruned)


def load_catalogue(source):
    """(kernels in definition order, file name) of a catalogue: a path to a .py file, a module, or a
    dotted module name."""
    if isinstance(source, (str, Path)) and (str(source).endswith(".py") or Path(source).is_file()):
        path = Path(source).resolve()
        name = f"_cgaskin_catalogue_{hashlib.sha256(str(path).encode()).hexdigest()[:12]}"
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or not path.is_file():
            raise CodegenError(f"catalogue {source}: no such file")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module                   # dataclasses and get_type_hints look it up
        try:
            spec.loader.exec_module(module)
        except Exception as exc:
            sys.modules.pop(name, None)
            raise CodegenError(f"catalogue {source}: importing it failed: {type(exc).__name__}: {exc}") from exc
        label = path.name
    else:
        module = importlib.import_module(source) if isinstance(source, str) else source
        label = Path(getattr(module, "__file__", None) or module.__name__).name
    kernels = [v for v in vars(module).values() if isinstance(v, KernelSpec)]
    if not kernels:
        raise CodegenError(f"catalogue {label}: defines no @kernel function")
    names = [k.name for k in kernels]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise CodegenError(f"catalogue {label}: kernels {dup} are defined twice")
    return kernels, label


def _check_names(spec, params):
    for name, _ in params:
        if name in RESERVED or name.startswith("_") or re.fullmatch(r"t\d+|l\d+_\d+|hoisted\d*|inv_weight", name):
            raise CodegenError(f"kernel {spec.name!r}: argument name {name!r} is reserved by the generated code")
    if spec.name.startswith("_") or spec.name in RESERVED:
        raise CodegenError(f"kernel name {spec.name!r} is reserved by the generated code")


def _divide(nums, den):
    if den is None:
        return [as_expr(n) for n in nums]
    d = as_expr(den)
    return [as_expr(n) if d == 1 else sympy.Mul(as_expr(n), sympy.Pow(d, -1)) for n in nums]


def compile_kernel(spec: KernelSpec) -> Compiled:
    """Trace ``spec`` on symbolic inputs; the scalar Kernel and, for uniform inputs, the hoisted stages."""
    params, ret = spec.signature()
    _check_names(spec, params)
    k = KernelBuilder(spec.name, spec.doc)
    declared = hoist.declare(k, params)
    names = [str(s) for _, _, syms in declared for s in syms]
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise CodegenError(f"kernel {spec.name!r}: arguments unpack into the same local names {clash}; rename one")
    with building(k.ring):
        args = [typ.value(k, syms) for _, typ, syms in declared]
        try:
            result = spec.fn(*args)
        except CodegenError as exc:                  # name the kernel where the message does not yet
            if f"kernel {spec.name!r}" in str(exc):
                raise
            raise CodegenError(f"kernel {spec.name!r}: {exc}") from exc
        except Exception as exc:                     # the catalogue's to fix: say which kernel, keep the cause
            raise CodegenError(f"kernel {spec.name!r}: tracing it raised {type(exc).__name__}: {exc}") from exc
        value = as_value(result)
        if value is None:
            raise CodegenError(f"kernel {spec.name!r}: returned {type(result).__name__}, not a cga value")
        pruned = hoist.versor_pruned(k, declared, value.mv, ret)
        labels, nums, den = ret.outputs(spec.name, pruned)
    dropped = tuple(ret.algebra.blade_display(m) for m in value.mv.blades if m not in pruned.terms)
    k.output(labels, _divide(nums, den))
    kernel = k.build()
    # hoisting splits polynomials: outputs with roots, functions or branches run unstaged
    polynomial = all(hasattr(x, "ring") for x in (*nums, den) if x is not None)
    stages = hoist.stage(spec, k, declared, nums, den) if spec.uniform and polynomial else None
    if stages is not None and opcount.total(opcount.op_counts(stages[1])) >= opcount.total(opcount.op_counts(kernel)):
        stages = None                                # hoisting would not save work per row
    return Compiled(spec, kernel, stages, spec.uniform, len(labels), dropped)


def _shape(typ, batch: bool) -> str:
    if typ.kind == "scalar":
        return "(N,)" if batch else "float"
    return f"(N, {typ.size})" if batch else f"({typ.size},)"


def _documented(c: Compiled, source: str) -> Kernel:
    """The scalar kernel with its docstring: the user's text, types, shapes and op counts."""
    params, ret = c.spec.signature()
    lines = [c.spec.doc or f"Kernel ``{c.spec.name}`` of {source}.", ""]
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


def _batch(c: Compiled) -> str:
    """``name_batch``: uniform inputs once, the others per row; hoisted stages when there are some."""
    if not c.uniform:
        return printer.print_batch(c.kernel)
    params, _ = c.spec.signature()
    names = [n for n, _ in params]
    shapes = ", ".join(f"{n} {_shape(t, n not in c.uniform)}" for n, t in params)
    what = (f"hoisted: ``_{c.spec.name}_uniform`` once, then ``_{c.spec.name}_row`` per row" if c.stages else
            "passed once; nothing is hoisted (it would not save work per row): the scalar kernel per row")
    lines = ["@njit(cache=True, error_model='numpy', nogil=True)",
             f"def {c.spec.name}_batch({', '.join(names)}, out):",
             f'    """``{c.spec.name}`` on every row: {shapes}; out (N, {c.out_size}).',
             "",
             f"    Uniform: {', '.join(c.uniform)}; {what}.",
             '    """']
    if c.stages:
        lines.append(f"    hoisted = _{c.spec.name}_uniform({', '.join(n for n in names if n in c.uniform)})")
        call = f"_{c.spec.name}_row(hoisted, {', '.join(f'{n}[row]' for n in names if n not in c.uniform)})"
    else:
        call = f"{c.spec.name}({', '.join(n if n in c.uniform else f'{n}[row]' for n in names)})"
    lines.append("    for row in range(out.shape[0]):")
    lines += printer.store_rows(call, c.out_size)
    return "\n".join(lines) + "\n"


def _algebras_line(compiled) -> str:
    """The algebras the catalogue's kernels are written in (the header's ``algebra:`` line)."""
    used = []
    for c in compiled:
        params, ret = c.spec.signature()
        for typ in [t for _, t in params] + [ret]:
            if typ.algebra not in used:
                used.append(typ.algebra)
    return "; ".join(headers.ALGEBRA if alg == algebras.cga else str(alg) for alg in used)


def report_table(compiled) -> str:
    """The op-count table of compiled kernels (``--report``): the scalar form, and for hoisted batch forms
    the per-row and once-per-call parts."""
    rows = []
    for c in compiled:
        rows.append((c.spec.name, opcount.op_counts(c.kernel), "scalar form"))
        if c.stages:
            rows.append(("  per row", opcount.op_counts(c.stages[1]), "batch form, hoisted"))
            rows.append(("  per call", opcount.op_counts(c.stages[0]), f"{len(c.stages[0].outputs)} hoisted values"))
    return opcount.table(rows)


def render(source) -> tuple[str, dict[str, str], str, list]:
    """(module text, {kernel name: its block of the text}, catalogue file name, compiled kernels)."""
    specs, label = load_catalogue(source)
    compiled = [compile_kernel(s) for s in specs]
    chunks = {}
    for c in compiled:
        parts = [printer.print_kernel(_documented(c, label))]
        if c.stages:
            parts += [printer.print_kernel(s) for s in c.stages]
        parts.append(_batch(c))
        chunks[c.spec.name] = "\n\n".join(parts)
    kernels = [c.kernel for c in compiled] + [s for c in compiled for s in (c.stages or ())]
    spec_hash = headers.digest("\n".join(k.spec_text for k in kernels))
    names = ", ".join(repr(c.spec.name) for c in compiled)
    body = "\n\n".join(["import math\n\nimport numpy as np\nfrom numba import njit\n", *chunks.values(),
                        f"KERNEL_NAMES = ({names},)\n"])
    header = "\n".join([f'"""Kernels of the catalogue {label} (scalar form and row loops).', "",
                        f"GENERATED by `cgaskin build --catalogue {label}` — do not edit by hand.",
                        f"generator: {headers.GENERATOR_VERSION}", f"{headers.SYMPY_LINE}{sympy.__version__}",
                        f"algebra: {_algebras_line(compiled)}", f"spec hash: {spec_hash}"]) + headers.HEADER_END
    return header + "\n" + body, chunks, label, compiled


def output_path(label: str, out) -> Path:
    """``out`` itself when it names a .py file, else ``out/<catalogue stem>.py``."""
    out = Path(out)
    return out if out.suffix == ".py" else out / (Path(label).stem + ".py")


def _target_files(compiled, label: str, targets, folder: Path) -> dict[Path, str]:
    """{path: text} of the catalogue's files for the targets other than numba (``codegen.targets``)."""
    from . import targets as printers
    kernels = [c.kernel for c in compiled]
    uniform = {c.spec.name: c.uniform for c in compiled if c.uniform}
    spec_hash = headers.digest("\n".join(k.spec_text for k in kernels))
    files = {}
    for target in targets:
        if target != "numba":
            header = headers.target_header(f"cgaskin build --catalogue {label} --target {target}", spec_hash,
                                         _algebras_line(compiled))
            for name, text in printers.render(target, kernels, prefix=Path(label).stem, header=header,
                                              uniform=uniform).items():
                files[folder / name] = text
    return files


def _stamped(file: Path, label: str) -> bool:
    """Whether ``file`` exists and carries the stamp of this catalogue's build (a file of that name
    without it is the user's own: never overwritten, never checked)."""
    try:
        with file.open(encoding="utf-8", errors="replace") as f:
            head = "".join(f.readline() for _ in range(20))
    except OSError:
        return False
    return f"GENERATED by `cgaskin build --catalogue {label}" in head


def _files(compiled, label: str, text: str, path: Path, targets, check: bool) -> tuple[tuple, dict]:
    """(targets, {path: text}) a build writes or a check compares: ``targets`` (None: numba and every
    other target whose stamped files are beside the module already, kept fresh as generated/'s are);
    a check also covers every target with a stamped file present, whatever ``targets`` says."""
    from .targets import TARGETS
    wanted = ("numba",) if targets is None else tuple(targets)
    unknown = [t for t in wanted if t not in TARGETS]
    if unknown:
        raise CodegenError(f"unknown target {unknown}; choose from {', '.join(TARGETS)}")
    # (each target's files are named <stem>...: without such a file beside the module, none is present)
    look = (targets is None or check) and any(f != path for f in path.parent.glob(glob.escape(path.stem) + "*"))
    printed = {t: _target_files(compiled, label, (t,), path.parent) for t in TARGETS[1:] if t in wanted or look}
    printed["numba"] = {path: text}
    if targets is None or check:
        present = {t for t, of_t in printed.items() if any(_stamped(f, label) for f in of_t)}
        wanted = tuple(t for t in TARGETS if t in wanted or t in present)
    return wanted, {f: s for t in wanted for f, s in printed[t].items()}


def build_catalogue(source, out, check: bool = False, log=print, report: bool = False, targets=None) -> int:
    """Write the files of a catalogue (or, with check=True, compare them): the numba module, and for
    each other target in ``targets`` its files beside it (``<stem>.h``, ``<stem>.glsl``, ...).
    ``targets`` None: numba and every target whose stamped files are there already; a check compares
    every stamped file present too (a hand-edited ``.h`` or ``.wgsl`` is stale whatever ``targets``
    says). Returns the number of stale kernels and files (a stale numba module counts its stale
    kernels, at least 1; 0 when up to date). ``report``: log the op-count table too."""
    start = time.perf_counter()
    text, chunks, label, compiled = render(source)
    if report:
        log(report_table(compiled))
    path = output_path(label, out)
    if isinstance(source, (str, Path)) and Path(source).resolve() == path.resolve():
        raise CodegenError(f"catalogue {source}: --out would overwrite the catalogue itself; choose another folder")
    targets, files = _files(compiled, label, text, path, targets, check)
    hint = f"run `cgaskin build --catalogue {label} --out {out}" + \
        (f" --target {','.join(targets)}`" if tuple(targets) != ("numba",) else "`")
    stale, written = 0, []
    for file, wanted in files.items():
        current = file.read_text(encoding="utf-8") if file.exists() else None
        if current is not None and headers.without_sympy_version(current) == headers.without_sympy_version(wanted):
            if not check and current != wanted:
                file.write_text(wanted, encoding="utf-8")
            continue
        if not check:
            file.parent.mkdir(parents=True, exist_ok=True)
            file.write_text(wanted, encoding="utf-8")
            written.append(file)
        elif current is None:
            log(f"stale: {file} does not exist; {hint}")
            stale += 1
        elif file == path:
            names = [name for name, chunk in chunks.items() if chunk not in current]
            for name in names:
                log(f"stale: {file}: kernel {name!r} differs from what {label} emits; {hint}")
            if not names:
                log(f"stale: {file}: the header or the kernel list differs from what {label} emits; {hint}")
            stale += max(1, len(names))
        else:
            log(f"stale: {file} differs from what {label} emits; {hint}")
            stale += 1
    timing = f"({len(chunks)} kernels, {time.perf_counter() - start:.1f} s)"
    if written:
        log(f"wrote {', '.join(map(str, written))} {timing}")
    elif not stale:
        log(f"{', '.join(map(str, files))} {'is' if len(files) == 1 else 'are'} up to date {timing}")
    return stale
