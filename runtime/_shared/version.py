"""cgaskin's version, in the lowest layer: ``cgaskin.__version__`` is this, and what the layers above
the facade read (a batch item's id holds it)."""

__all__ = ["VERSION"]

#: the release (pyproject.toml's ``version``)
VERSION = "0.1.0"
