"""three.js plays every file cgaskin writes as cgaskin does: GLTFLoader in headless Chromium, each
clip through AnimationMixer (LoopOnce, clamped: glTF's sampling), skinned positions read with
SkinnedMesh.getVertexPosition in world space, per vertex in file order, against ``cgaskin.skin`` in
the rest pose and at key times, between keys and past the end of every clip (1e-5 of the diagonal).

One browser for all files: tests/clients/js/skin_positions.mjs, the files served from 127.0.0.1."""
import base64
import functools
import json
import os
import subprocess
import threading
import time
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

from .conftest import SUMMARY
from .files import NAMES, expected

TOLERANCE = 1e-5  # of the bounding box diagonal: float32 storage and three.js's float32 weights


class _Handler(SimpleHTTPRequestHandler):
    """tests/clients/js (page, node_modules) at /, the files under test at /files/."""
    extensions_map = {**SimpleHTTPRequestHandler.extensions_map, ".mjs": "text/javascript",
                      ".js": "text/javascript", ".glb": "model/gltf-binary", ".gltf": "model/gltf+json"}

    def __init__(self, *args, files: Path, **kwargs):
        self.files = files
        super().__init__(*args, **kwargs)

    def translate_path(self, path):
        name = path.split("?")[0]
        if name.startswith("/files/") and "/" not in name[7:] and ".." not in name:
            return str(self.files / name[7:])
        return super().translate_path(path)

    def log_message(self, *args):
        pass


@pytest.fixture(scope="module")
def threejs_results(threejs, client_files, models_dir, tmp_path_factory):
    """name -> (Expected, (poses, n, 3) positions three.js computed), from one browser run."""
    start = time.perf_counter()
    wanted = {name: expected(client_files[name], models_dir) for name in NAMES}
    jobs = [{"url": f"files/{name}", "poses": [[clip, t] for clip, t in e.poses]} for name, e in wanted.items()]
    work = tmp_path_factory.mktemp("threejs")
    (work / "jobs.json").write_text(json.dumps(jobs))
    handler = functools.partial(_Handler, files=next(iter(client_files.values())).parent, directory=str(threejs["js"]))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        run = subprocess.run([threejs["node"], str(threejs["js"] / "skin_positions.mjs"),
                              f"http://127.0.0.1:{server.server_address[1]}", str(work / "jobs.json"),
                              str(work / "out.json")], capture_output=True, text=True, timeout=180,
                             env={**os.environ, "CGASKIN_CHROMIUM": threejs["chromium"]})
    finally:
        server.shutdown()
        server.server_close()
    assert run.returncode == 0, f"skin_positions.mjs failed:\n{run.stderr[-4000:]}"
    results = {}
    for (name, e), result in zip(wanted.items(), json.loads((work / "out.json").read_text())):
        assert "error" not in result, f"three.js could not play {name}: {result['error']}"
        positions = np.frombuffer(base64.b64decode(result["positions"]), dtype="<f8")
        results[name] = (e, result, positions.reshape(len(e.poses), result["vertices"], 3))
    n_poses = sum(len(e.poses) for e in wanted.values())
    SUMMARY.append(f"three.js: {len(results)} files, {sum(len(e.positions[0]) for e in wanted.values())} "
                   f"vertices, {n_poses} poses ({sum(len(e.positions[0]) * len(e.poses) for e in wanted.values())} "
                   f"skinned vertices) compared in {time.perf_counter() - start:.1f} s, one Chromium")
    return results


@pytest.mark.parametrize("name", NAMES)
def test_threejs_plays_the_file_as_cgaskin_does(threejs_results, name):
    e, result, positions = threejs_results[name]
    assert result["meshes"] >= 1
    assert positions.shape[1] == len(e.positions[0]), "three.js holds another number of vertices"
    if e.rig is not None:
        assert result["clips"] == [clip.name for clip in e.rig.clips]
    worst = []
    for (clip, t), mine, theirs in zip(e.poses, e.positions, positions):
        error = np.abs(theirs - mine).max() / e.diagonal
        worst.append((error, clip, t))
    error, clip, t = max(worst, key=lambda w: w[0])
    assert error <= TOLERANCE, (f"{name}: three.js differs from cgaskin.skin by {error:.2e} of the diagonal "
                                f"({'rest pose' if clip is None else f'clip {clip!r} at t={t}'})")
