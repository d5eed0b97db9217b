"""Fixtures of the codegen tests."""
import sys

import pytest


@pytest.fixture(scope="module", autouse=True)
def _print_worst_errors():
    """After each kernel test module, the worst relative error its tests recorded per kernel (seen with
    ``-s``); the registry is tests.helpers.kernel_oracles.WORST, loaded only by the kernel tests."""
    yield
    oracles = sys.modules.get("tests.helpers.kernel_oracles")
    if oracles is not None and oracles.WORST:
        print("\nworst relative errors per kernel (this run):")
        for name in sorted(oracles.WORST):
            print(f"  {name:34s} {oracles.WORST[name]:.3g}")
        oracles.WORST.clear()
