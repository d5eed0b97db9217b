"""Helpers shared by the tests: hypothesis strategies, tolerances, the independent glTF oracle."""
