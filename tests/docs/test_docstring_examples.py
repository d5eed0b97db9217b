"""The Examples sections of the public API's docstrings run (doctest), so that the reference's examples
cannot rot: every public function, class and method of the modules the reference covers, with
``np`` (NumPy) and ``cgaskin`` in their namespace."""
from __future__ import annotations

import doctest
import importlib
import inspect

import numpy as np
import pytest

from .test_inventory import _api

API = _api()
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def documented_objects(module_name: str):
    """(qualified name, object) of each public name of the module and each public member of its
    classes that has a docstring of its own."""
    module = importlib.import_module(module_name)
    for name in API.public_names(module_name):
        obj = getattr(module, name)
        yield f"{module_name}.{name}", obj
        if inspect.isclass(obj):
            for member, value in vars(obj).items():
                if not member.startswith("_") and getattr(value, "__doc__", None):
                    yield f"{module_name}.{name}.{member}", value


@pytest.mark.parametrize("module_name", API.MODULES)
def test_the_examples_of_the_docstrings_run(module_name, tmp_path, monkeypatch):
    import cgaskin
    monkeypatch.chdir(tmp_path)
    finder, runner = doctest.DocTestFinder(recurse=False), doctest.DocTestRunner(optionflags=FLAGS)
    failed = []
    for qualified, obj in documented_objects(module_name):
        doc = obj.__doc__ if isinstance(obj.__doc__, str) else None
        if not doc or ">>>" not in doc:
            continue
        for test in finder.find(obj, qualified, globs={"np": np, "cgaskin": cgaskin}):
            result = runner.run(test, out=lambda text: failed.append(text))
            if result.failed:
                failed.append(f"{qualified}: {result.failed} of {result.attempted} examples failed")
    assert not failed, "\n".join(failed)
