"""What the C and CUDA target tests share: the comparison of a
target's rows with numba's, the C compiler, and the Fox model posed at a clip time."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np

from tests.helpers.requirements import require  # noqa: F401 (test_cuda imports it from here)

#: the flags every generated C source must compile under without a diagnostic (the issue's -Wall
#: -Werror, and the warnings a strict C project adds: shadowing, implicit conversions, float ==)
C_FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Wshadow", "-Wconversion", "-Wdouble-promotion",
           "-Wfloat-equal", "-Werror", "-O2", "-ffp-contract=off"]


def c_compiler() -> str:
    """The C compiler (env CC, else cc) and cffi, or skip/fail."""
    cc = shutil.which(os.environ.get("CC", "cc"))
    missing = [] if cc else ["a C compiler (cc)"]
    try:
        import cffi  # noqa: F401
    except ImportError:
        missing.append("cffi (PyPI)")
    require(missing, "the C target test")
    return cc


def compile_c(cc: str, source: Path, output: Path, extra=()) -> None:
    """Compile ``source`` with ``C_FLAGS`` (+ ``extra``); any diagnostic fails the test."""
    result = subprocess.run([cc, *C_FLAGS, *extra, str(source), "-o", str(output), "-lm"],
                            capture_output=True, text=True)
    assert result.returncode == 0 and not result.stderr.strip() and not result.stdout.strip(), \
        f"{' '.join([cc, *C_FLAGS, *extra, source.name])}:\n{result.stdout}{result.stderr}"


def assert_rows_close(what: str, got, ref, tol: float, inputs=None) -> None:
    """|got - ref| <= tol * max(1, max_j |ref[row, j]|) in every row (the row's scale: a kernel's
    outputs share units, so an output that cancels to ~0 is judged against its row's magnitude);
    NaN where numba gives NaN, and the same infinities, count as equal."""
    got, ref = np.asarray(got, np.float64), np.asarray(ref, np.float64)
    assert got.shape == ref.shape, f"{what}: shape {got.shape} != {ref.shape}"
    finite = np.isfinite(ref)
    same_special = (np.isnan(ref) & np.isnan(got)) | (np.isinf(ref) & (got == ref))
    scale = np.maximum(1.0, np.max(np.where(finite, np.abs(ref), 0.0), axis=-1, keepdims=True))
    with np.errstate(invalid="ignore"):
        ok = same_special | (finite & (np.abs(got - ref) <= tol * scale))
    if not ok.all():
        row = int(np.argwhere(~ok)[0][0])
        detail = "" if inputs is None else f"\ninputs of row {row}: {[np.asarray(a)[row].tolist() for a in inputs]}"
        with np.errstate(invalid="ignore"):
            err = np.nanmax(np.where(finite & ~ok, np.abs(got - ref) / scale, 0.0))
        raise AssertionError(f"{what}: {int((~ok).sum())} outputs differ (worst finite scaled error {err:.3g}, tolerance {tol}; NaN/inf mismatches count as differences); "
                             f"row {row}: got {got[row].tolist()}, numba {ref[row].tolist()}{detail}")


def input_spread(module, kernel, inputs, eps: float, copies: int = 4, seed: int = 0) -> np.ndarray:
    """(rows,) D: the largest change of numba's float64 result over ``copies`` copies of each row's
    inputs with every entry moved by one relative ``eps`` (random sign): what rounding the inputs to
    a precision of that ``eps`` alone may change. inf where the move changes whether an output is
    finite (the row sits on a singularity)."""
    from tests.helpers.target_cases import reference
    rng = np.random.default_rng(seed)
    ref = reference(module, kernel, inputs)
    spread = np.zeros(len(ref))
    for _ in range(copies):
        moved = tuple(a * (1.0 + eps * rng.choice([-1.0, 1.0], size=a.shape)) for a in inputs)
        other = reference(module, kernel, moved)
        with np.errstate(invalid="ignore"):
            change = np.where(np.isfinite(ref) & np.isfinite(other), np.abs(other - ref),
                              np.where((np.isnan(ref) & np.isnan(other)) | (ref == other), 0.0, np.inf))
        spread = np.maximum(spread, change.max(axis=1))
    return spread


def assert_rows_close_float(what: str, got, ref, spread, tol: float, inputs=None) -> None:
    """A float result against numba's float64 one on the same (float-rounded) inputs:
    |got - ref| <= tol * S + 16 D per output (S the row's scale as in ``assert_rows_close``, D its
    ``input_spread`` at float's eps: a row that rounding an input by one float ulp changes by more than
    tol * S is ill-conditioned, and float arithmetic inside the kernel rounds by that much and more).
    Where numba's output is not finite nothing is asserted of the float one: such a row sits on a
    singularity of the kernel (a singular matrix, a zero axis), where float rounding decides whether a
    division or a square root meets exactly 0 or a negative (a singular matrix with two equal rows gave
    NaN in float64 and finite values in float). The double test asserts the same NaN. Nor is anything
    asserted of a row whose 16 D reaches its scale S (as in the GLSL test): float cannot give one digit
    of it (a nearly singular matrix that a float ulp of input moved by 1e5, where float's rounding met a
    negative square root and numba's did not)."""
    got, ref = np.asarray(got, np.float64), np.asarray(ref, np.float64)
    finite = np.isfinite(ref)
    scale = np.maximum(1.0, np.max(np.where(finite, np.abs(ref), 0.0), axis=-1, keepdims=True))
    d = spread[:, None]
    with np.errstate(invalid="ignore"):
        close = finite & (np.abs(got - ref) <= tol * scale + 16.0 * d)
    with np.errstate(invalid="ignore"):
        ok = close | ~finite | (16.0 * d >= scale)          # d = inf (a singular row) included
    if not ok.all():
        row = int(np.argwhere(~ok)[0][0])
        detail = "" if inputs is None else f"\ninputs of row {row}: {[np.asarray(a)[row].tolist() for a in inputs]}"
        raise AssertionError(f"{what}: {int((~ok).sum())} outputs differ beyond {tol} x scale + 16 D; row {row}: "
                             f"got {got[row].tolist()}, numba {ref[row].tolist()}, D {spread[row]:.3g}{detail}")


def user_catalogue(tmp_path_factory):
    """``user_kernels`` built once per session for both the C and the CUDA tests (one folder, so its
    cache hits): (Kernel IRs, uniform dict, numba module)."""
    from tests.helpers.target_cases import user_kernels
    return user_kernels(str(tmp_path_factory.getbasetemp() / "c_cuda_user_catalogue"))


def fox_posed(models_dir: Path, clip: str = "Run", time: float = 0.37):
    """(rig, pose) of the shared Fox.glb at ``time`` seconds into ``clip``."""
    import cgaskin
    rig = cgaskin.load(models_dir / "Fox.glb")
    return rig, rig.pose(clip, time)
