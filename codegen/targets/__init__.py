"""Printers of the kernel IR (``codegen.ir.Kernel``) for targets outside numba: C99, GLSL, WGSL, CUDA,
JavaScript.

Every target module has the same entry point:

    render(kernels, *, prefix, header, uniform=None, skinning=False) -> {file name: text}

kernels   the scalar ``Kernel`` IRs in catalogue order
prefix    the name prefix: kernel ``k`` becomes ``<prefix>_k``; the files are ``<prefix>.<ext>`` and
          ``<prefix>_skin.<ext>`` (``"cgaskin"`` for the built-in catalogue, the file stem for a user's)
header    lines for the file's leading comment (GENERATED ..., generator, spec hash), put in each file
uniform   {kernel name: names of its inputs the batch form takes once}
skinning  also emit the skinning loop/shader (needs ``versor_to_affine`` and ``affine_point``)

Layouts are the numba kernels' (flat arrays in the blade order of generated/layout.py); expressions are
printed by ``codegen.expressions`` in each target's ``Dialect``.
"""
from __future__ import annotations

import importlib

from ..ir import CodegenError

#: every target ``cgaskin build --target`` knows; numba is the default (``codegen.printer``)
TARGETS = ("numba", "c", "glsl", "wgsl", "cuda", "js")


def parse_targets(text: str) -> tuple[str, ...]:
    """('numba', 'c', ...) of a comma-separated ``--target`` value; CodegenError naming an unknown one."""
    names = tuple(dict.fromkeys(t.strip() for t in text.split(",") if t.strip()))
    unknown = [t for t in names if t not in TARGETS]
    if unknown or not names:
        raise CodegenError(f"--target {text!r}: unknown target {unknown or text!r}; choose from {', '.join(TARGETS)}")
    return names


def render(target: str, kernels, *, prefix: str, header, uniform=None, skinning: bool = False) -> dict[str, str]:
    """{file name: text} of one target other than numba (the contract above)."""
    module = importlib.import_module(f"{__name__}.{target}")
    return module.render(kernels, prefix=prefix, header=list(header), uniform=uniform or {}, skinning=skinning)
