"""Build a user's catalogue of ``@kernel`` functions (``codegen.language``) into one numba module.

    build_catalogue("mykernels.py", "mypkg/generated")          # writes mypkg/generated/mykernels.py
    build_catalogue("mykernels.py", "mypkg/generated", check=True)   # 0 when up to date
    cgaskin build --catalogue mykernels.py --out mypkg/generated [--check]

The module holds, per kernel, ``name(...)`` (the scalar form: inputs as 1-D arrays or floats, returns
a float or a tuple of floats) and ``name_batch(..., out)`` (every row: uniform inputs single, the
others (N, ...), out (N, k)); a stamped header as generated/kernels.py has; each kernel's docstring
holds its symbolic expansion and its operation counts. It imports numpy and numba only.

Uniform inputs (``@kernel(uniform=("V",))``) are hoisted when that saves work per row
(``codegen.trace``). The module and the other targets' files go through the one build pipeline
(``codegen.pipeline``) that generated/ goes through; this module chooses what goes in, which targets and
where their files go.
"""
from __future__ import annotations

import glob
import time
from pathlib import Path

from . import algebras, headers, pipeline
from .ir import CodegenError
from .trace import Compiled, compile_kernel, load_catalogue

__all__ = ["Compiled", "build_catalogue", "compile_kernel", "load_catalogue", "output_path", "user_catalogue"]


def _algebras_line(compiled) -> str:
    """The algebras the catalogue's kernels are written in (the header's ``algebra:`` line)."""
    used = []
    for c in compiled:
        params, ret = c.spec.signature()
        for typ in [t for _, t in params] + [ret]:
            if typ.algebra not in used:
                used.append(typ.algebra)
    return "; ".join(headers.ALGEBRA if alg == algebras.cga else str(alg) for alg in used)


def user_catalogue(source) -> pipeline.Catalogue:
    """A user's catalogue (a .py file, a module, or a dotted module name) as the pipeline builds it."""
    specs, label = load_catalogue(source)
    compiled = tuple(compile_kernel(s) for s in specs)
    return pipeline.Catalogue(
        compiled=compiled, label=label, command=f"cgaskin build --catalogue {label}",
        title=f"Kernels of the catalogue {label} (scalar form and row loops).", prefix=Path(label).stem,
        algebra=_algebras_line(compiled), documented=True)


def output_path(label: str, out) -> Path:
    """``out`` itself when it names a .py file, else ``out/<catalogue stem>.py``."""
    out = Path(out)
    return out if out.suffix == ".py" else out / (Path(label).stem + ".py")


def _stamped(file: Path, cat: pipeline.Catalogue) -> bool:
    """Whether ``file`` exists and carries the stamp of this catalogue's build (a file of that name
    without it is the user's own: never overwritten, never checked)."""
    try:
        with file.open(encoding="utf-8", errors="replace") as f:
            head = "".join(f.readline() for _ in range(20))
    except OSError:
        return False
    return headers.generated_by(cat.command) in head


def _files(cat: pipeline.Catalogue, text: str, path: Path, targets, check: bool) -> tuple[tuple, dict]:
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
    printed = {t: {path.parent / name: s for name, s in pipeline.target_files(cat, t).items()}
               for t in TARGETS[1:] if t in wanted or look}
    printed["numba"] = {path: text}
    if targets is None or check:
        present = {t for t, of_t in printed.items() if any(_stamped(f, cat) for f in of_t)}
        wanted = tuple(t for t in TARGETS if t in wanted or t in present)
    return wanted, {f: s for t in wanted for f, s in printed[t].items()}


def build_catalogue(source, out, check: bool = False, log=print, report: bool = False, targets=None) -> int:
    """Compile a catalogue of ``@kernel`` functions into a numba module and other targets' files.

    What ``cgaskin build --catalogue FILE --out DIR`` runs (needs sympy, the ``build`` extra).

    Parameters
    ----------
    source : str or os.PathLike or module
        The catalogue: a .py file, a module, or a dotted module name.
    out : str or os.PathLike
        The folder of the generated files (or the .py file of the numba module).
    check : bool, optional
        Compare the files with what the catalogue emits now instead of writing them.
    log : callable, optional
        Called with each line to report (default: ``print``).
    report : bool, optional
        Log each kernel's operation counts too.
    targets : sequence of str, optional
        Of "numba", "c", "glsl", "wgsl", "cuda", "js": each target's files go beside the numba
        module (``<stem>.h``, ``<stem>.glsl``, ...). None: numba and every target whose generated
        files are there already; a check compares every generated file present too (a hand-edited
        ``.h`` is stale whatever ``targets`` says).

    Returns
    -------
    int
        The number of stale kernels and files (a stale numba module counts its stale kernels, at
        least 1); 0 when up to date.

    Raises
    ------
    CodegenError
        A kernel the language cannot compile (the message names it and why).

    Examples
    --------
    >>> from cgaskin.codegen import build_catalogue
    >>> with open("mykernels.py", "w") as file:
    ...     _ = file.write('''
    ... from cgaskin.codegen import cga, kernel
    ...
    ... @kernel
    ... def reflect(plane: cga.Plane, x: cga.Point) -> cga.Point:
    ...     return -plane * x * plane
    ... ''')
    >>> build_catalogue("mykernels.py", "out", targets=("numba", "c"))   # doctest: +SKIP
    wrote out/mykernels.py, out/mykernels.h, out/mykernels_f32.h (1 kernels, 0.2 s)
    0
    """
    start = time.perf_counter()
    cat = user_catalogue(source)
    text, chunks = pipeline.numba_module(cat)
    if report:
        log(pipeline.report_table(cat))
    path = output_path(cat.label, out)
    if isinstance(source, (str, Path)) and Path(source).resolve() == path.resolve():
        raise CodegenError(f"catalogue {source}: --out would overwrite the catalogue itself; choose another folder")
    targets, files = _files(cat, text, path, targets, check)
    hint = f"run `{cat.command} --out {out}" + (f" --target {','.join(targets)}`" if tuple(targets) != ("numba",) else "`")
    done = pipeline.sync(files, check, cat.label, hint, chunks={path: chunks})
    for message in done.messages:
        log(message)
    timing = f"({len(chunks)} kernels, {time.perf_counter() - start:.1f} s)"
    if done.written:
        log(f"wrote {', '.join(map(str, done.written))} {timing}")
    elif not done.stale:
        log(f"{', '.join(map(str, files))} {'is' if len(files) == 1 else 'are'} up to date {timing}")
    return done.stale
