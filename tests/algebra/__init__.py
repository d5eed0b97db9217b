"""Tests of cgaskin.algebra: versors and transform helpers."""
