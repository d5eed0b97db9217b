"""Write (or check) ``generated/``: the built-in catalogue (``codegen.catalogue``) through the build
pipeline (``codegen.pipeline``), and the two modules only it has.

Modules:
    layout.py     blade orders and sizes shared by codegen and runtime (``codegen.layouts``, as constants)
    kernels.py    every catalogue kernel (scalar form) and its ``_batch`` row loop
    skinning.py   the hoisted skinning blend loops (serial and prange), built on kernels.py
and for each other target present (``--target``) its files in ``generated/<target>/``.

Each header records the generator version, the sympy version, the algebra, a hash of the kernel
specs, and the hashes of the generated modules it imports: numba's on-disk cache keys on a file's own
contents only, so a changed callee in another file must change the caller's text too.
``--check`` ignores the sympy version on the ``sympy:`` line (it records which sympy wrote the file;
a new release that emits the same kernels is not a reason to rebuild); every other byte counts.
"""
from __future__ import annotations

import time
from pathlib import Path

import sympy

from . import catalogue, layouts, pipeline, printer
from .headers import digest, python_header, stamp, without_sympy_version
from .ir import CodegenError
from .trace import Compiled

GENERATED_DIR = Path(__file__).resolve().parent.parent / "generated"
COMMAND = "cgaskin build"
SOURCE = "codegen/"


def builtin() -> pipeline.Catalogue:
    """The built-in catalogue as the pipeline builds it."""
    return pipeline.Catalogue(
        compiled=tuple(Compiled.of(make()) for make in catalogue.KERNELS), label=SOURCE, command=COMMAND,
        title="CGA kernels (scalar form and row loops).", prefix="cgaskin", source=SOURCE, skinning=True,
        decorator=printer.RUNTIME_DECORATOR)


def _header(title: str, spec_hash: str, imports: dict[str, str]) -> str:
    return python_header(title, stamp(COMMAND, spec_hash, imports=imports, source=SOURCE))


def layout_module() -> str:
    from . import algebra
    disp = lambda blades: tuple(algebra.blade_display(algebra.mask_of(b)) for b in blades)  # noqa: E731
    body = [
        f"VERSOR_BLADES = {disp(layouts.VERSOR)!r}",
        f"MOTOR_BLADES = {disp(layouts.MOTOR)!r}",
        f"PLANE_BLADES = {disp(layouts.PLANE)!r}",
        f"LOG_BLADES = {disp(layouts.LOG)!r}",
        f"AFFINE_LABELS = {layouts.AFFINE_LABELS!r}",
        f"VERSOR_SIZE = {len(layouts.VERSOR)}",
        f"MOTOR_SIZE = {len(layouts.MOTOR)}",
        f"PLANE_SIZE = {len(layouts.PLANE)}",
        f"LOG_SIZE = {len(layouts.LOG)}",
        f"IDENTITY_VERSOR = (1.0,) + (0.0,) * {len(layouts.VERSOR) - 1}",
    ]
    text = "\n".join(body) + "\n"
    return _header("Blade orders of the generated kernels' array layouts.", digest(text), {}) + "\n" + text


def skinning_module(kernels_hash: str, affine) -> str:
    # The blend is only valid when the per-vertex kernel is linear in the per-bone coefficients:
    # then Σ w_k f(A_k, x) = f(Σ w_k A_k, x), one kernel call per vertex instead of k.
    coeffs = [s for i in affine.inputs if i.name == "a" for s in i.symbols]
    for e in affine.outputs:
        if sympy.Poly(e, *coeffs).total_degree() > 1:
            raise CodegenError("affine_point is not linear in its coefficients: cannot blend them")
    n = len(coeffs)
    loop = [f"        a{j} = 0.0" for j in range(n)]
    inner = ["            row = affines[b]"] + [f"            a{j} += w * row[{j}]" for j in range(n)]
    blend_args = ", ".join(f"a{j}" for j in range(n))

    def blend(name, decorator, rng):
        return "\n".join([
            decorator,
            f"def {name}(rest, joints, weights, affines, out):",
            '    """out[i] = (Σ_k weights[i,k] affines[joints[i,k]]) applied to rest[i].',
            "",
            "    rest : (n, 3) float64, joints : (n, k) int, weights : (n, k) float,",
            "    affines : (B, 12) float64 from versor_to_affine, out : (n, 3) float64 (written).",
            "    Returns (influences with a joint index outside [0, B), negative (or NaN) weights, vertices",
            "    with a non-finite result); an index is checked before it is read, and a bad one is skipped.",
            "    Checking here costs nothing measurable: the loop is memory-bound and the branches are never",
            "    taken.",
            '    """',
            "    n_bones = affines.shape[0]",
            "    bad_joints = 0",
            "    bad_weights = 0",
            "    bad_values = 0",
            f"    for i in {rng}(rest.shape[0]):",
            *loop,
            "        for k in range(joints.shape[1]):",
            "            w = weights[i, k]",
            "            if not w >= 0.0:",
            "                bad_weights += 1",
            "            b = joints[i, k]",
            "            if b < 0 or b >= n_bones:",
            "                bad_joints += 1",
            "                continue",
            *inner,
            f"        x = affine_point(({blend_args}), rest[i])",
            "        out[i, 0] = x[0]",
            "        out[i, 1] = x[1]",
            "        out[i, 2] = x[2]",
            "        if not x[0] * 0.0 + x[1] * 0.0 + x[2] * 0.0 == 0.0:    # false for NaN and inf",
            "            bad_values += 1",
            "    return bad_joints, bad_weights, bad_values",
        ]) + "\n"

    body = "\n\n".join([
        "from numba import njit, prange\n\nfrom .kernels import affine_point\n",
        # no fast-math, not even 'contract' (a += w * r fused into one FMA where the CPU has it): the
        # same bits on every machine, from the shipped kernels (a portable CPU without FMA) and from
        # kernels compiled on the host alike
        blend("skin_blend", printer.RUNTIME_DECORATOR, "range"),
        blend("skin_blend_parallel", "@njit(error_model='numpy', nogil=True, parallel=True)", "prange"),
    ])
    return _header("Hoisted skinning: blend per-bone affine coefficients, apply once per vertex.",
                   digest(body), {"kernels": kernels_hash}) + "\n" + body


def _render(targets=("numba",)) -> tuple[dict[str, str], dict[str, str]]:
    """({path under generated/: text}, {kernel name: its block of kernels.py})."""
    cat = builtin()
    kernels_text, chunks = pipeline.numba_module(cat)
    affine = next(c.kernel for c in cat.compiled if c.name == "affine_point")
    files = {
        "__init__.py": '"""Generated CGA kernels (see codegen/). Do not edit by hand."""\n',
        "layout.py": layout_module(),
        "kernels.py": kernels_text,
        # hashed without the sympy version: a callee whose code is unchanged must not change the caller
        "skinning.py": skinning_module(digest(without_sympy_version(kernels_text)), affine),
    }
    for target in targets:
        if target != "numba":
            files.update((f"{target}/{name}", text) for name, text in pipeline.target_files(cat, target).items())
    return files, chunks


def render(targets=("numba",)) -> dict[str, str]:
    """{path under generated/: text}: the numba modules, and ``<target>/...`` for each other target."""
    return _render(targets)[0]


def present_targets(directory: Path = GENERATED_DIR) -> tuple[str, ...]:
    """numba and every other target that has a folder in ``directory`` (they are kept fresh too)."""
    from .targets import TARGETS
    return ("numba",) + tuple(t for t in TARGETS[1:] if (directory / t).is_dir())


def report_table() -> str:
    """The op-count table of the built-in kernels (``cgaskin build --report``)."""
    return pipeline.report_table(builtin())


def build(check: bool = False, directory: Path = GENERATED_DIR, log=print, report: bool = False,
          targets=None) -> int:
    """Write generated/ (or, with check=True, compare it). Returns the number of stale kernels and files
    (a stale kernels.py counts its stale kernels; 0 after a build). ``report``: log the op-count table
    too. ``targets``: the printers to run (default: numba and every target already in generated/); the
    others' files are written to ``generated/<target>/``. A check compares every target already in
    generated/ as well: ``--check`` covers every stamped file there."""
    start = time.perf_counter()
    if targets is None or check:        # a check covers every target in generated/, whatever --target says
        targets = (*present_targets(directory), *(targets or ()))
    targets = tuple(dict.fromkeys(("numba", *targets)))
    files, chunks = _render(targets)
    if report:
        log(report_table())
    done = pipeline.sync({directory / name: text for name, text in files.items()}, check, SOURCE,
                         f"run `{COMMAND}`", chunks={directory / "kernels.py": chunks},
                         shown=lambda path: f"generated/{path.relative_to(directory).as_posix()}")
    for message in done.messages:
        log(message)
    elapsed = time.perf_counter() - start
    if check and not done.stale:
        log(f"generated/ is up to date ({len(files)} files, {elapsed:.1f} s)")
    elif not check:
        log(f"wrote {len(done.written)} of {len(files)} files in generated/ ({elapsed:.1f} s)")
    return done.stale
