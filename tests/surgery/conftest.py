"""Fixtures of the surgery tests."""
import pytest

from tests.helpers.tear_checks import MODELS, get_rig


@pytest.fixture(scope="module", params=MODELS)
def tear_model(request):
    """(name, rig); the file models skip without the models folder."""
    name = request.param
    if name == "capsule":
        return name, get_rig(name)
    return name, get_rig(name, request.getfixturevalue("models_dir"))
