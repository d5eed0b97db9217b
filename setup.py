"""Tags a wheel that carries the compiled kernels (runtime/_kernels) for the Python and platform they
serve, not ``py3-none-any``: the kernels are machine code for one platform, pickled by one Python.
Everything else is in pyproject.toml."""
import json
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.bdist_wheel import bdist_wheel


def layers() -> list:
    """The names of the compiled layers that have a manifest (``cp311-linux_x86_64-numpy2.4``)."""
    folder = Path(__file__).resolve().parent / "runtime" / "_kernels"
    return sorted(path.parent.name for path in folder.glob("*/manifest.json")
                  if json.loads(path.read_text(encoding="utf-8")).get("kernels"))


class KernelsDistribution(Distribution):
    def has_ext_modules(self):          # platform-specific files: the wheel's root is platlib
        return bool(layers())


class KernelsWheel(bdist_wheel):
    def get_tag(self):
        names = layers()
        if not names:                   # a source tree without compiled kernels: a pure wheel
            return super().get_tag()
        pythons = sorted({name.split("-")[0] for name in names})
        platforms = sorted({name.split("-")[1] for name in names})
        return ".".join(pythons), pythons[0] if len(pythons) == 1 else "none", ".".join(platforms)


setup(distclass=KernelsDistribution, cmdclass={"bdist_wheel": KernelsWheel})
