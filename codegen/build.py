"""Write (or check) ``generated/``: the catalogue printed as numba modules with stamped headers
(``codegen.headers``), and for ``--target`` the other targets' files in ``generated/<target>/``.

Modules:
    layout.py     blade orders and sizes shared by codegen and runtime (plain constants)
    kernels.py    every catalogue kernel (scalar form) and its ``_batch`` row loop
    skinning.py   the hoisted skinning blend loops (serial and prange), built on kernels.py

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

from . import catalogue, printer
from .headers import digest as _digest, python_header as _header, target_header
from .headers import without_sympy_version as _without_sympy_version
from .ir import CodegenError

GENERATED_DIR = Path(__file__).resolve().parent.parent / "generated"


def layout_module() -> str:
    from .catalogue import AFFINE_LABELS, LOG, MOTOR, PLANE, VERSOR
    from . import algebra
    disp = lambda blades: tuple(algebra.blade_display(algebra.mask_of(b)) for b in blades)  # noqa: E731
    body = [
        f"VERSOR_BLADES = {disp(VERSOR)!r}",
        f"MOTOR_BLADES = {disp(MOTOR)!r}",
        f"PLANE_BLADES = {disp(PLANE)!r}",
        f"LOG_BLADES = {disp(LOG)!r}",
        f"AFFINE_LABELS = {AFFINE_LABELS!r}",
        "VERSOR_SIZE = 12",
        "MOTOR_SIZE = 8",
        "PLANE_SIZE = 4",
        "LOG_SIZE = 7",
        "IDENTITY_VERSOR = (1.0,) + (0.0,) * 11",
    ]
    text = "\n".join(body) + "\n"
    return _header("Blade orders of the generated kernels' array layouts.", _digest(text), {}) + "\n" + text


def kernels_module(kernels) -> tuple[str, str]:
    spec_hash = _digest("\n".join(k.spec_text for k in kernels))
    parts = ["import math\n\nimport numpy as np\nfrom numba import njit\n"]
    for k in kernels:
        parts.append(printer.print_kernel(k))
        parts.append(printer.print_batch(k))
    names = ", ".join(repr(k.name) for k in kernels)
    parts.append(f"KERNEL_NAMES = ({names},)\n")
    body = "\n\n".join(parts)
    return _header("CGA kernels (scalar form and row loops).", spec_hash, {}) + "\n" + body, spec_hash


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
        # 'contract' lets LLVM fuse a += w * r into one FMA (one rounding instead of two: no less
        # accurate, ~8% faster); no other fast-math flag (the results must stay IEEE-exact otherwise)
        blend("skin_blend", "@njit(cache=True, error_model='numpy', nogil=True, fastmath={'contract'})", "range"),
        blend("skin_blend_parallel",
              "@njit(cache=True, error_model='numpy', nogil=True, parallel=True, fastmath={'contract'})", "prange"),
    ])
    return _header("Hoisted skinning: blend per-bone affine coefficients, apply once per vertex.",
                   _digest(body), {"kernels": kernels_hash}) + "\n" + body


def render(targets=("numba",)) -> dict[str, str]:
    """{path under generated/: text}: the numba modules, and ``<target>/...`` for each other target."""
    from . import targets as printers
    kernels = [make() for make in catalogue.KERNELS]
    kernels_text, spec_hash = kernels_module(kernels)
    affine = next(k for k in kernels if k.name == "affine_point")
    files = {
        "__init__.py": '"""Generated CGA kernels (see codegen/). Do not edit by hand."""\n',
        "layout.py": layout_module(),
        "kernels.py": kernels_text,
        # hashed without the sympy version: a callee whose code is unchanged must not change the caller
        "skinning.py": skinning_module(_digest(_without_sympy_version(kernels_text)), affine),
    }
    for target in targets:
        if target != "numba":
            header = target_header(f"cgaskin build --target {target}", spec_hash)
            for name, text in printers.render(target, kernels, prefix="cgaskin", header=header, skinning=True).items():
                files[f"{target}/{name}"] = text
    return files


def present_targets(directory: Path = GENERATED_DIR) -> tuple[str, ...]:
    """numba and every other target that has a folder in ``directory`` (they are kept fresh too)."""
    from .targets import TARGETS
    return ("numba",) + tuple(t for t in TARGETS[1:] if (directory / t).is_dir())


def report_table() -> str:
    """The op-count table of the built-in kernels (``cgaskin build --report``)."""
    from . import opcount
    return opcount.table([(k.name, opcount.op_counts(k), "") for k in (make() for make in catalogue.KERNELS)])


def build(check: bool = False, directory: Path = GENERATED_DIR, log=print, report: bool = False,
          targets=None) -> int:
    """Write generated/ (or, with check=True, compare it). Returns the number of stale files. ``report``:
    log the op-count table too. ``targets``: the printers to run (default: numba and every target
    already in generated/); the others' files are written to ``generated/<target>/``. A check
    compares every target already in generated/ as well: ``--check`` covers every stamped file there."""
    start = time.perf_counter()
    if targets is None or check:        # a check covers every target in generated/, whatever --target says
        targets = (*present_targets(directory), *(targets or ()))
    targets = tuple(dict.fromkeys(("numba", *targets)))
    files = render(targets)
    if report:
        log(report_table())
    stale = []
    for name, text in files.items():
        path = directory / name
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if check:
            differs = current is None or _without_sympy_version(current) != _without_sympy_version(text)
        else:
            differs = current != text
        if differs:
            stale.append(name)
            if not check:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text, encoding="utf-8")
    elapsed = time.perf_counter() - start
    if check:
        for name in stale:
            log(f"stale: generated/{name} differs from what codegen/ emits; run `cgaskin build`")
        if not stale:
            log(f"generated/ is up to date ({len(files)} files, {elapsed:.1f} s)")
    else:
        log(f"wrote {len(stale)} of {len(files)} files in generated/ ({elapsed:.1f} s)")
    return len(stale)
