"""Model subcommands of the ``cgaskin`` command line (demo, skin, cut, tear)."""
from __future__ import annotations


def register(sub) -> None:
    """Add the model subcommands to the argparse subparsers ``sub``."""
