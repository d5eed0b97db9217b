"""Printers of the kernel IR (``codegen.ir.Kernel``) for targets outside numba: C99, GLSL, WGSL, CUDA.

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
