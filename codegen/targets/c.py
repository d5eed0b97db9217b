"""The C99 target's ``render`` (the contract of ``codegen.targets``): the kernel headers printed by
``c_kernels`` (double and float), the skinning headers by ``c_skinning``."""
from __future__ import annotations

from .c_kernels import header_source
from .c_skinning import skin_header_source


def render(kernels, *, prefix: str, header, uniform=None, skinning: bool = False) -> dict[str, str]:
    """{``<prefix>.h`` and ``<prefix>_f32.h``: the kernels in double and float, and with ``skinning``
    ``<prefix>_skin.h`` and ``<prefix>_skin_f32.h``: the skinning stages}."""
    files = {f"{prefix}.h": header_source(kernels, prefix, header, uniform),
             f"{prefix}_f32.h": header_source(kernels, prefix, header, uniform, "float")}
    if skinning:
        files[f"{prefix}_skin.h"] = skin_header_source(kernels, prefix, header)
        files[f"{prefix}_skin_f32.h"] = skin_header_source(kernels, prefix, header, "float")
    return files
