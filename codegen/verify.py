"""Verification for free: every kernel of a catalogue run three ways on drawn inputs of its declared types.

    verify_catalogue("mykernels.py", examples=50)        # a Report; VerificationError on any failure
    cgaskin verify --catalogue mykernels.py [--examples N] [--out DIR]

Per kernel and input: (1) the generated module (scalar kernel, and the batch kernel: uniform inputs once,
the rows stacked), (2) the same Python function evaluated on ``clifford`` multivectors (G(4,1) of
``clifford.conformalize(Cl(3))``, e∞ = e− + e+, e0 = ½(e− − e+) as here; the language's values wrap
them, ``|`` is the left contraction ``<<``, ``.dual()`` is X I⁻¹ with I = e1∧e2∧e3∧e∞∧e0), (3) float64
evaluation of the symbolic expansion (sympy ``lambdify`` of the kernel's expanded outputs: no CSE, no
staging, no hoisting). Points enter as up(x) and leave down-projected (Euclidean part over e0).

Inputs are drawn with ``numpy.random.default_rng(seed)`` (deterministic): coordinates signed
log-uniform in [1e-3, cap], planes with unit normals and |d| ≤ cap, versors as ``versor.motor(axis,
angle ∈ [0, π] (π itself included), translation with |t_i| ≤ cap)`` composed with ``versor.dilator(s ∈
[0.01, 100])`` (Versor only), scalars ±[0.01, 100], generic multivectors N(0,1)·10^U(−1,1).
``examples`` inputs at the full range (cap 1e4) are compared generated vs expansion; ``examples`` more at
moderate range (cap 10) are also compared against clifford (whose up/down loses ~ε|x|² at |x| = 1e4).

Tolerances: |generated − expansion| ≤ 1e-12·|result| + 64 ε S and |generated − clifford| ≤ 1e-9·|result| +
64 ε S, where |result| is the largest output magnitude and S the sum of the magnitudes of the expansion's
terms (for a down-projected point (Sₙ + |x|·S_w)/|w|): 64 ε S bounds what float64 can reach by any
evaluation order. Where that bound exceeds 1e-12·|result| the report says so ("conditioning") instead
of failing. Any exception or non-finite output in any path is a failure.
"""
from __future__ import annotations

import importlib.util
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

try:
    import clifford  # noqa: F401  (verify_clifford needs it: fail here with the install hint)
    import sympy
except ImportError as exc:                                   # pragma: no cover - depends on the install
    raise ImportError(f"cgaskin verify needs sympy and clifford: pip install 'cgaskin[test]' ({exc})") from exc

from . import algebras
from .catalogue_build import build_catalogue, output_path
from .functions import magnitude
from .layouts import VERSOR
from .trace import compile_kernel, load_catalogue
from .values import as_value, building
from .verify_clifford import CliffordMV, backend

TOL_EXPANSION = 1e-12
TOL_CLIFFORD = 1e-9
SLACK = 64
EPS = float(np.finfo(float).eps)
FULL, MODERATE = 1e4, 10.0
_CGA = algebras.cga


class VerificationError(Exception):
    """A kernel disagrees between its three evaluations, or one of them raised."""

    def __init__(self, message, report=None):
        super().__init__(message)
        self.report = report


# -- drawing inputs ---------------------------------------------------------------------------------
def _signed_log(rng, lo, hi, size=None):
    return rng.choice([-1.0, 1.0], size) * np.exp(rng.uniform(np.log(lo), np.log(hi), size))


def _unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def draw(typ, rng, cap: float, index: int = 0):
    """One input of type ``typ`` (see the module docstring for the ranges); ``index`` 0 takes angle π."""
    from ..algebra import versor
    if typ.kind == "scalar":
        return float(_signed_log(rng, 0.01, 100.0))
    if typ.kind == "point" or typ.name == "Vector":
        return _signed_log(rng, 1e-3, cap, 3)
    if typ.space == "pga":
        return _draw_pga(typ, rng, cap, index)
    if typ.name == "Plane":
        return np.concatenate([_unit(rng), [_signed_log(rng, 1e-3, cap)]])
    if typ.name == "Sphere":
        c, r = _signed_log(rng, 1e-3, cap, 3), float(np.exp(rng.uniform(np.log(1e-2), np.log(cap))))
        return np.concatenate([c, [0.5 * (c @ c - r * r), 1.0]])
    if typ.name == "Line":
        from .language import cga
        return _meet(cga.Plane, typ, rng, cap)
    if typ.versor:
        angle = np.pi if index == 0 else rng.uniform(0.0, np.pi)
        t = (0.0, 0.0, 0.0) if typ.name == "Rotor" else _signed_log(rng, 1e-3, cap, 3)
        v = versor.motor(_unit(rng), angle, t)
        if typ.name == "Versor":
            v = versor.compose(v, versor.dilator(float(np.exp(rng.uniform(np.log(0.01), np.log(100.0))))))
        names = [_CGA.blade_name(_CGA.mask_of(n)) for n in VERSOR]
        return np.array([v[names.index(n)] for n in typ.blades])
    return rng.normal(size=typ.size) * 10.0 ** rng.uniform(-1, 1, typ.size)


def _meet(plane, line, rng, cap):
    """A line: the meet (outer product) of two drawn planes."""
    be = backend(plane.algebra)
    p, q = (be.value(plane, draw(plane, rng, cap)).mv for _ in range(2))
    return be.result(line, p ^ q)


def _draw_pga(typ, rng, cap, index):
    """PGA inputs: planes (unit normal, |d| ≤ cap), lines as meets, unit rotors cos(θ/2) + sin(θ/2) n·(e12,
    e13, e23) (θ ∈ [0, π], π itself at index 0), translators 1 + ½ t·(e01, e02, e03), motors T R."""
    from .language_pga import pga
    if typ.name == "Plane":
        return np.concatenate([_unit(rng), [_signed_log(rng, 1e-3, cap)]])
    if typ.name == "Line":
        return _meet(pga.Plane, typ, rng, cap)
    if not typ.versor:
        return rng.normal(size=typ.size) * 10.0 ** rng.uniform(-1, 1, typ.size)
    angle = np.pi if index == 0 else rng.uniform(0.0, np.pi)
    rotor = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * _unit(rng)])
    translator = np.concatenate([[1.0], 0.5 * _signed_log(rng, 1e-3, cap, 3)])
    if typ.name in ("Rotor", "Translator"):
        return rotor if typ.name == "Rotor" else translator
    be = backend(typ.algebra)
    motor = be.value(pga.Translator, translator).mv * be.value(pga.Rotor, rotor).mv
    return be.result(typ, motor)


# -- the symbolic expansion in float64 --------------------------------------------------------------
class Expansion:
    """The kernel's expanded outputs (numerator / weight) and their term-magnitude bounds, lambdified."""

    def __init__(self, kernel):
        syms = [s for inp in kernel.inputs for s in inp.symbols]
        outs = list(kernel.outputs)
        for sym, value in reversed(kernel.lets):           # the scalar kernel has none; be safe anyway
            outs = [o.xreplace({sym: value}) for o in outs]
        nums, dens = zip(*(sympy.fraction(o) for o in outs))

        def bound(p):                                       # evaluated at the inputs themselves
            if not p.is_polynomial(*syms):                  # scalar functions: codegen.functions
                return magnitude(p)
            poly = sympy.Poly(sympy.expand(p), *syms)
            return sympy.Add(*(abs(c) * sympy.Mul(*(abs(s) ** e for s, e in zip(syms, mon)))
                               for mon, c in poly.terms()))

        self.value = sympy.lambdify(syms, list(outs), "math")
        self.num = sympy.lambdify(syms, list(nums), "math")
        self.den = sympy.lambdify(syms, list(dens), "math")
        self.bnum = sympy.lambdify(syms, [bound(n) for n in nums], "math")
        self.bden = sympy.lambdify(syms, [bound(d) if d != 1 else sympy.Integer(0) for d in dens], "math")

    def __call__(self, flat):
        """(values, S): the outputs and the per-output magnitude bound of their terms."""
        a = [float(v) for v in flat]
        num, den = np.array(self.num(*flat), float), np.array(self.den(*flat), float)
        val = num / den
        s = (np.array(self.bnum(*a), float) + np.abs(val) * np.array(self.bden(*a), float)) / np.abs(den)
        return val, s


# -- the report -------------------------------------------------------------------------------------
@dataclass
class KernelReport:
    name: str
    examples: int = 0
    err_clifford: float = 0.0         # worst relative error, generated vs clifford (moderate range)
    err_expansion: float = 0.0        # worst relative error, generated (scalar and batch) vs expansion
    reach: float = 0.0                # worst 64 ε S / |result|: what float64 can reach (full range)
    failures: list = field(default_factory=list)     # (severity, message), the worst first

    @property
    def ok(self) -> bool:
        return not self.failures

    @property
    def conditioning(self) -> str | None:
        if self.reach <= TOL_EXPANSION:
            return None
        return (f"{self.name}: conditioning: float64 evaluation (any order) reaches only {self.reach:.1e} "
                f"relative on some inputs (cancellation among terms up to |x| = {FULL:g}); compared within "
                f"64 ε S there")


@dataclass
class Report:
    label: str
    kernels: list

    @property
    def ok(self) -> bool:
        return all(k.ok for k in self.kernels)

    def failure_text(self) -> str:
        return "; ".join(f"kernel {k.name!r}: {k.failures[0][1]}" + (f" (and {len(k.failures) - 1} more)"
                                                                   if len(k.failures) > 1 else "")
                         for k in self.kernels if k.failures)

    def table(self) -> str:
        rows = [("kernel", "examples", "vs clifford", "vs expansion", "status")]
        rows += [(k.name, str(k.examples), f"{k.err_clifford:.1e}", f"{k.err_expansion:.1e}",
                  "ok" if k.ok else "FAIL") for k in self.kernels]
        widths = [max(len(r[i]) for r in rows) for i in range(5)]
        lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
        lines += [k.conditioning for k in self.kernels if k.conditioning]
        lines += [f"{k.name}: FAIL: {f}" for k in self.kernels for _, f in k.failures[:3]]
        lines.append(f"tolerances: vs expansion {TOL_EXPANSION:g} relative (inputs up to {FULL:g}); vs clifford "
                     f"{TOL_CLIFFORD:g} relative (inputs up to {MODERATE:g}: clifford's up/down loses ~ε|x|² "
                     f"beyond); each + 64 ε S (S: sum of the magnitudes of the expansion's terms)")
        return "\n".join(lines)


# -- running one kernel three ways ------------------------------------------------------------------
def _fmt(params, args) -> str:
    return ", ".join(f"{n}={np.array2string(np.asarray(a), precision=17, separator=', ', max_line_width=10**6)}"
                     for (n, _), a in zip(params, args))


def _compare(a, b, s, tol):
    """(relative error, passed) of ``a`` against the reference ``b`` with term bound ``s``."""
    a, b, s = (np.atleast_1d(np.asarray(v, float)) for v in (a, b, s))
    if a.shape != b.shape or not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return float("inf"), False
    size = float(np.max(np.abs(b)))
    err = np.abs(a - b)
    scale = max(size, SLACK * EPS * float(np.max(s)), 1e-300)
    return float(np.max(err)) / scale, bool(np.all(err <= tol * size + SLACK * EPS * s))


def _verify_kernel(spec, module, examples: int, seed: int) -> KernelReport:
    import zlib
    rep = KernelReport(spec.name, examples)
    try:
        params, ret = spec.signature()
        expansion = Expansion(compile_kernel(spec).kernel)
        scalar_fn, batch_fn = getattr(module, spec.name), getattr(module, f"{spec.name}_batch")
    except Exception as exc:  # noqa: BLE001 - e.g. a module built from another version of the catalogue
        rep.failures.append((float("inf"), f"setting up raised {type(exc).__name__}: {exc}"))
        return rep
    uniform = set(spec.uniform)
    be = backend(ret.algebra)
    rng = np.random.default_rng([seed, zlib.crc32(spec.name.encode())])

    def flat(args):
        return [float(v) for a in args for v in np.atleast_1d(a)]

    def fail(message, args, severity=float("inf")):
        rep.failures.append((severity, f"{message} at {_fmt(params, args)}"))
        rep.failures.sort(key=lambda f: -f[0])          # the worst first

    def check(label, got, ref, s, tol, args, attr):
        err, ok = _compare(got, ref, s, tol)
        setattr(rep, attr, max(getattr(rep, attr), err))
        if not ok:
            fail(f"{label}: relative error {err:.1e} beyond {tol:g} (+64 ε S)", args, err)

    def run(label, fn, args):
        try:
            return fn()
        except Exception as exc:  # noqa: BLE001 - any exception in any path is a failure, reported
            fail(f"{label} raised {type(exc).__name__}: {exc}", args)
            return None

    for cap in (FULL, MODERATE):
        drawn = [[draw(t, rng, cap, i) for _, t in params] for i in range(examples)]
        for i, args in enumerate(drawn):
            ref = run("expansion", lambda: expansion(flat(args)), args)
            got = run("generated", lambda: np.atleast_1d(np.asarray(scalar_fn(*args), float)), args)
            if ref is None:
                continue
            ref_v, s = ref
            rep.reach = max(rep.reach, SLACK * EPS * float(np.max(s)) / max(float(np.max(np.abs(ref_v))), 1e-300))
            if got is not None:
                check("generated vs expansion", got, ref_v, s, TOL_EXPANSION, args, "err_expansion")
            # the batch form: uniform inputs of this example, rows of this example and the next
            rows = [args, [args[p] if n in uniform else drawn[(i + 1) % examples][p]
                           for p, (n, _) in enumerate(params)]]
            stacked = [a if n in uniform else np.array([np.asarray(r[p], float) for r in rows])
                       for p, ((n, _), a) in enumerate(zip(params, args))]
            out = np.zeros((2, len(ref_v)))
            if run("batch", lambda: (batch_fn(*stacked, out), 0)[1], args) is not None:
                for r, row_args in enumerate(rows):
                    row_ref = run("expansion", lambda: expansion(flat(row_args)), row_args)
                    if row_ref is not None:
                        check("batch vs expansion", out[r], row_ref[0], row_ref[1], TOL_EXPANSION, row_args,
                              "err_expansion")
            if cap == MODERATE and got is not None:
                cl = run("clifford", lambda: _clifford_call(spec, params, ret, args, be), args)
                if cl is not None:
                    check("generated vs clifford", got, cl, s, TOL_CLIFFORD, args, "err_clifford")
    return rep


def _clifford_call(spec, params, ret, args, be):
    with building(be):
        values = [be.value(t, a) for (_, t), a in zip(params, args)]
        result = as_value(spec.fn(*values))
        if result is None or not isinstance(result.mv, CliffordMV):
            raise TypeError(f"the kernel returned {type(result).__name__}, not a cga value")
        return be.result(ret, result.mv)


def _import(path: Path, cache_dir: str):
    """The generated module, registered in sys.modules, its numba cache in ``cache_dir`` (not next to
    the module: a cache written when another program imported it under another name does not load)."""
    import hashlib
    import sys

    import numba
    key = f"{path.resolve()}:{path.stat().st_mtime_ns}".encode()
    name = f"_cgaskin_verify_{hashlib.sha256(key).hexdigest()[:16]}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    saved, numba.config.CACHE_DIR = numba.config.CACHE_DIR, cache_dir
    try:
        spec.loader.exec_module(module)                 # the decorators pick their cache folder now
    finally:
        numba.config.CACHE_DIR = saved
    return module


def verify_catalogue(source, out=None, examples: int = 50, rebuild: bool = True, seed: int = 0,
                     log=None) -> Report:
    """Check every kernel of a catalogue against clifford and its own symbolic expansion.

    Builds ``source``, then runs every kernel three ways (generated code, clifford, the expansion)
    on drawn inputs per range (module docstring). Needs sympy and clifford.

    Parameters
    ----------
    source : str or os.PathLike or module
        The catalogue, as ``build_catalogue`` takes it.
    out : str or os.PathLike, optional
        The folder to build into (default: a temporary one).
    examples : int, optional
        Inputs drawn per kernel and range, >= 1.
    rebuild : bool, optional
        False: verify the module already in ``out`` as it is.
    seed : int, optional
        Seed of the drawn inputs.
    log : callable, optional
        Called with the build's lines (default: silent).

    Returns
    -------
    Report
        Each kernel's worst relative errors; ``.ok`` is True.

    Raises
    ------
    VerificationError
        A disagreement or an exception: the message names each failing kernel and its worst input,
        ``.report`` holds the Report.

    Examples
    --------
    >>> from cgaskin.codegen import verify_catalogue
    >>> report = verify_catalogue("mykernels.py", examples=5)      # doctest: +SKIP
    >>> report.ok, [kernel.name for kernel in report.kernels]       # doctest: +SKIP
    (True, ['reflect'])
    """
    from .ir import CodegenError
    if examples < 1:
        raise CodegenError(f"examples={examples}: need at least 1")
    specs, label = load_catalogue(source)
    tmp = tempfile.TemporaryDirectory(prefix="cgaskin_verify_") if out is None else None
    cache = tempfile.TemporaryDirectory(prefix="cgaskin_verify_cache_")
    try:
        folder = tmp.name if tmp else out
        if rebuild or tmp:
            build_catalogue(source, folder, log=log or (lambda *a: None))
        path = output_path(label, folder)
        if not path.is_file():
            raise CodegenError(f"catalogue {label}: no generated module at {path}; build it first")
        module = _import(path, cache.name)
        report = Report(label, [_verify_kernel(s, module, examples, seed) for s in specs])
    finally:
        cache.cleanup()
        if tmp:
            tmp.cleanup()
    if not report.ok:
        raise VerificationError(report.failure_text(), report)
    return report
