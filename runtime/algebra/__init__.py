"""The algebra layer: versors of G(4,1) over the generated kernels, and plain transform helpers."""
