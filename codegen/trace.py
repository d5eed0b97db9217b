"""Trace ``@kernel`` functions (``codegen.language``) into kernel IR: each input declared by its type,
the function called once on symbolic values, the result checked against its return type.

``compile_kernel`` gives the scalar ``Kernel`` and, for uniform inputs (``@kernel(uniform=("V",))``),
the hoisted stages: every output is written as a polynomial in the per-row symbols whose coefficients
are polynomials in the uniform ones (divided by the result's down-projection weight when that depends
on uniforms only); those coefficients are computed once per call (``_name_uniform``) and the row loop
calls ``_name_row`` on them. For a versor sandwich on a point this finds the 3×4 affine map that
``versor_to_affine`` stages by hand. The staging is kept only when it saves work per row (counted after
CSE); otherwise the row loop calls the scalar kernel with the uniform inputs passed once.
``load_catalogue`` finds the ``@kernel`` functions of a file or module.
"""
from __future__ import annotations

import hashlib
import importlib
import importlib.util
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import sympy

from . import hoist, opcount
from .ir import CodegenError, Kernel, KernelBuilder, as_expr
from .language import KernelSpec
from .values import as_value, building

RESERVED = {"out", "row", "r", "hoisted", "math", "np", "njit"}


@dataclass(frozen=True)
class Compiled:
    """A kernel as the build pipeline (``codegen.pipeline``) prints it."""

    spec: KernelSpec | None           # None: a built-in kernel written with the builder (``ir.KernelBuilder``)
    kernel: Kernel                    # the scalar form
    stages: tuple | None              # (uniform Kernel, row Kernel) when the batch form is hoisted
    uniform: tuple                    # names of the uniform inputs
    out_size: int
    dropped: tuple = ()               # blades dropped as zero for versor inputs (_versor_pruned)

    @classmethod
    def of(cls, kernel: Kernel) -> "Compiled":
        """A kernel IR with no spec behind it: no uniform inputs, no stages."""
        return cls(None, kernel, None, (), len(kernel.outputs))

    @property
    def name(self) -> str:
        return self.kernel.name


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
