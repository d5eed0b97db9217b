"""Every module of the reference says what it exports (``__all__``), and the package's facade and its
errors export exactly their public names; ``cgaskin.codegen`` exports the error a bad kernel raises."""
from __future__ import annotations

import importlib
import types

import pytest

from .test_inventory import _api

API = _api()


@pytest.mark.parametrize("module_name", API.MODULES)
def test_every_module_of_the_reference_has_an_all(module_name):
    module = importlib.import_module(module_name)
    names = getattr(module, "__all__", None)
    assert names is not None, f"{module_name} has no __all__"
    assert len(set(names)) == len(names) and all(hasattr(module, name) for name in names)


@pytest.mark.parametrize("module_name", ["cgaskin", "cgaskin.errors"])
def test_the_all_of_the_facade_and_the_errors_is_every_public_name(module_name):
    module = importlib.import_module(module_name)
    public = {name for name, value in vars(module).items()
              if not name.startswith("_") and not isinstance(value, types.ModuleType)}
    assert set(module.__all__) == public


def test_codegen_exports_its_own_error():
    import cgaskin.codegen
    from cgaskin.codegen.errors import CodegenError
    assert "CodegenError" in cgaskin.codegen.__all__ and cgaskin.codegen.CodegenError is CodegenError
    assert not issubclass(CodegenError, importlib.import_module("cgaskin.errors").CgaskinError)
