"""Generated CGA kernels (see codegen/). Do not edit by hand."""
