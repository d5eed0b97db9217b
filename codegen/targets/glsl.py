"""The GLSL target's ``render`` (the contract of ``codegen.targets``): the kernel includes printed by
``glsl_kernels`` (double and float), the skinning shaders by ``glsl_skin``."""
from __future__ import annotations

from .glsl_kernels import include
from .glsl_skin import skin_files


def render(kernels, *, prefix, header, uniform=None, skinning=False) -> dict:
    """{file name: text}: ``<prefix>.glsl`` and ``<prefix>_f32.glsl``; with ``skinning`` also the
    shaders of ``glsl_skin.skin_files``."""
    files = {f"{prefix}.glsl": include(kernels, prefix, header, True, uniform),
             f"{prefix}_f32.glsl": include(kernels, prefix, header, False, uniform)}
    if skinning:
        files.update(skin_files(kernels, prefix, header))
    return files
