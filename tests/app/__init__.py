"""Tests of cgaskin.app: the command line and precompile."""
