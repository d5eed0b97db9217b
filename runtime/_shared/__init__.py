"""Helpers every layer uses (argument checks)."""
