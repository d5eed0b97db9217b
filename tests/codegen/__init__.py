"""Tests of cgaskin.codegen and the kernels it emits into cgaskin.generated."""
