"""glTF external resources stay in the model's folder: buffer URIs that point outside it (``..``,
absolute paths, ``file:`` and other schemes, percent-encoded forms, symlinks) are refused with a
``ModelFormatError`` naming the URI and the rule, and the outside file is never opened; relative
URIs into subfolders, percent-encoded or not, keep loading."""
import base64
import builtins
import io
import json
import os
import pathlib

import numpy as np
import pytest

import cgaskin
from cgaskin.errors import ModelFormatError
from cgaskin.rigs.gltf import load_gltf

RULE = "external resources must lie in the model's folder or below it"


# --- building the files ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def arm_gltf(tmp_path_factory):
    """(JSON document, buffer bytes) of capsule_arm saved as .gltf (buffer embedded as data:)."""
    path = tmp_path_factory.mktemp("saved") / "arm.gltf"
    cgaskin.save(cgaskin.capsule_arm(), path)
    doc = json.loads(path.read_text())
    uri = doc["buffers"][0]["uri"]
    assert uri.startswith("data:") and len(doc["buffers"]) == 1
    return doc, base64.b64decode(uri.partition(",")[2])


@pytest.fixture(scope="module")
def reference(arm_gltf, tmp_path_factory):
    """The rig loaded from the saved file with its embedded buffer."""
    doc, _ = arm_gltf
    path = tmp_path_factory.mktemp("embedded") / "arm.gltf"
    path.write_text(json.dumps(doc))
    return load_gltf(path)


@pytest.fixture
def layout(tmp_path, arm_gltf):
    """tmp_path/model/ holds the model; tmp_path/secret.bin, outside it, holds a buffer that would
    load (so a loader that read it would succeed): returns (model folder, secret path, write)."""
    doc, blob = arm_gltf
    model = tmp_path / "model"
    model.mkdir()
    secret = tmp_path / "secret.bin"
    secret.write_bytes(blob)

    def write(uri: str) -> pathlib.Path:
        """arm.gltf in the model folder with buffer 0 pointing at ``uri``."""
        edited = json.loads(json.dumps(doc))
        edited["buffers"][0]["uri"] = uri
        path = model / "arm.gltf"
        path.write_text(json.dumps(edited))
        return path

    return model, secret, write


@pytest.fixture
def opened(monkeypatch):
    """Every path the code under test opens (builtins/io/os.open, Path.open), resolved."""
    seen: list[pathlib.Path] = []

    def record(target):
        if isinstance(target, (str, bytes, os.PathLike)):
            try:
                seen.append(pathlib.Path(os.fsdecode(target)).resolve())
            except (OSError, ValueError):
                seen.append(pathlib.Path(os.fsdecode(target)))

    def spy(original):
        def wrapper(*args, **kwargs):
            record(args[0] if args else kwargs.get("file", kwargs.get("path")))
            return original(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(builtins, "open", spy(builtins.open))
    monkeypatch.setattr(io, "open", spy(io.open))
    monkeypatch.setattr(os, "open", spy(os.open))
    monkeypatch.setattr(pathlib.Path, "open", spy(pathlib.Path.open))
    return seen


def assert_same_rig(rig, reference):
    assert np.array_equal(rig.vertices, reference.vertices)
    assert np.array_equal(rig.faces, reference.faces)
    assert np.array_equal(rig.joints, reference.joints)
    assert np.array_equal(rig.weights, reference.weights)
    assert rig.skeleton.n_bones == reference.skeleton.n_bones


def assert_refused(path, uri, secret, opened):
    """Loading ``path`` raises ModelFormatError naming the file, the URI and the rule; ``secret``
    exists and was never opened."""
    assert secret.is_file()
    opened.clear()  # only what loading opens counts, not the test's own setup
    with pytest.raises(ModelFormatError) as info:
        load_gltf(path)
    message = str(info.value)
    assert path.name in message
    assert repr(uri) in message
    assert RULE in message
    assert secret.resolve() not in opened, f"{secret} was opened while loading {uri!r}"
    return message


# --- refused --------------------------------------------------------------------------------------

# each template is formatted with secret = the outside file's absolute path (POSIX)
REFUSED = {
    "parent": "../secret.bin",
    "parent_after_subfolder": "buffers/../../secret.bin",
    "parent_through_missing_folder": "missing/../../secret.bin",
    "dot_then_parent": "./../secret.bin",
    "percent_parent": "..%2Fsecret.bin",
    "percent_dots": "%2E%2E/secret.bin",
    "percent_everything": "%2E%2E%2F%73ecret.bin",
    "absolute": "{secret}",
    "percent_absolute": "%2F{secret_rest}",
    "network_path": "//localhost{secret}",
    "file_uri": "file://{secret}",
    "file_uri_no_host": "file:{secret}",
    "file_uri_upper": "FILE://{secret}",
}


@pytest.mark.parametrize("template", REFUSED.values(), ids=REFUSED.keys())
def test_uri_outside_the_folder_is_refused(layout, opened, template):
    model, secret, write = layout
    (model / "buffers").mkdir()
    uri = template.format(secret=secret.as_posix(), secret_rest=secret.as_posix().lstrip("/"))
    assert_refused(write(uri), uri, secret, opened)


@pytest.mark.parametrize("uri", ["/etc/passwd", "file:///etc/passwd", "%2Fetc%2Fpasswd",
                                 "../../../../../../../../etc/passwd"])
def test_system_files_are_refused(layout, opened, uri):
    _, _, write = layout
    outside = pathlib.Path("/etc/passwd")
    if not outside.is_file():
        pytest.skip("no /etc/passwd on this system")
    assert_refused(write(uri), uri, outside, opened)


@pytest.mark.parametrize("uri", ["http://example.com/arm.bin", "https://example.com/arm.bin",
                                 "ftp://example.com/arm.bin", "smb://host/share/arm.bin"])
def test_other_schemes_are_refused(layout, opened, uri):
    _, secret, write = layout
    assert "data:" in assert_refused(write(uri), uri, secret, opened)


def test_symlink_to_a_file_outside_is_refused(layout, opened):
    model, secret, write = layout
    (model / "arm.bin").symlink_to(secret)
    assert_refused(write("arm.bin"), "arm.bin", secret, opened)


def test_symlinked_folder_outside_is_refused(layout, opened, tmp_path, arm_gltf):
    model, _, write = layout
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    target = outside / "arm.bin"
    target.write_bytes(arm_gltf[1])
    (model / "buffers").symlink_to(outside, target_is_directory=True)
    assert_refused(write("buffers/arm.bin"), "buffers/arm.bin", target, opened)


def test_percent_encoded_symlink_outside_is_refused(layout, opened):
    model, secret, write = layout
    (model / "my arm.bin").symlink_to(secret)
    assert_refused(write("my%20arm.bin"), "my%20arm.bin", secret, opened)


def test_symlink_loop_is_a_clear_error(layout):
    model, _, write = layout
    (model / "a.bin").symlink_to("b.bin")
    (model / "b.bin").symlink_to("a.bin")
    with pytest.raises(ModelFormatError, match="arm.gltf: buffer 0 uri 'a.bin'"):
        load_gltf(write("a.bin"))


def test_nul_byte_is_a_clear_error(layout):
    _, _, write = layout
    with pytest.raises(ModelFormatError, match="arm.gltf.*NUL"):
        load_gltf(write("arm%00.bin"))


# --- allowed --------------------------------------------------------------------------------------

def test_file_next_to_the_model_loads(layout, reference, arm_gltf):
    model, _, write = layout
    (model / "arm.bin").write_bytes(arm_gltf[1])
    assert_same_rig(load_gltf(write("arm.bin")), reference)


def test_subfolder_loads(layout, reference, arm_gltf):
    model, _, write = layout
    (model / "buffers").mkdir()
    (model / "buffers" / "a.bin").write_bytes(arm_gltf[1])
    assert_same_rig(load_gltf(write("buffers/a.bin")), reference)


@pytest.mark.parametrize("uri", ["sub%20dir/a.bin", "sub%20dir%2Fa.bin", "%73ub%20dir/a.bin",
                                 "./sub dir/a.bin", "sub%20dir/../sub%20dir/a.bin"])
def test_percent_encoded_and_dotted_uris_inside_load(layout, reference, arm_gltf, uri):
    model, _, write = layout
    (model / "sub dir").mkdir()
    (model / "sub dir" / "a.bin").write_bytes(arm_gltf[1])
    assert_same_rig(load_gltf(write(uri)), reference)


def test_symlink_inside_the_folder_loads(layout, reference, arm_gltf):
    model, _, write = layout
    (model / "buffers").mkdir()
    (model / "buffers" / "a.bin").write_bytes(arm_gltf[1])
    (model / "link.bin").symlink_to(pathlib.Path("buffers") / "a.bin")
    assert_same_rig(load_gltf(write("link.bin")), reference)


def test_model_folder_reached_through_a_symlink_loads(layout, reference, arm_gltf, tmp_path):
    model, _, write = layout
    (model / "arm.bin").write_bytes(arm_gltf[1])
    write("arm.bin")
    alias = tmp_path / "alias"
    alias.symlink_to(model, target_is_directory=True)
    assert_same_rig(load_gltf(alias / "arm.gltf"), reference)


def test_missing_file_inside_still_says_missing(layout):
    _, _, write = layout
    with pytest.raises(ModelFormatError, match="missing"):
        load_gltf(write("buffers/nothere.bin"))


def test_data_uri_still_loads(layout, reference, arm_gltf):
    _, _, write = layout
    uri = "data:application/octet-stream;base64," + base64.b64encode(arm_gltf[1]).decode()
    assert_same_rig(load_gltf(write(uri)), reference)
