"""Joints that three.js names alike: it drops '.', ':', '/' and brackets from node names and makes the
results unique with a suffix, so the page's bone "arm1" may be the model's joint "arm.1". A dilation
made in the page must reach the server under the model's name of the joint the page scaled."""
import dataclasses
import json
import os
import subprocess

import numpy as np

import cgaskin
from cgaskin.serve import Server

from tests.helpers.requirements import require

from .test_serve import MISSING

NAMES = ["shoulder", "arm.1", "arm1"]        # three.js: "shoulder", and "arm1" / "arm1_1" in some order
FACTORS = {"arm1": 1.5, "arm1_1": 0.6}       # set in the page, by its bone names


def test_a_dilation_set_in_the_page_reaches_the_server_under_the_models_joint_name(threejs, tmp_path):
    require(MISSING, "cgaskin serve's tests")
    arm = cgaskin.capsule_arm()
    rig = dataclasses.replace(arm, skeleton=dataclasses.replace(arm.skeleton, names=NAMES))
    clip = rig.clips[0].name
    steps = [[0, "call", "pause"], [0, "call", "setTime", 0.0]]
    steps += [[0, "call", "setDilation", bone, factor] for bone, factor in FACTORS.items()]
    steps += [[0, "call", "positions"], [0, "call", "surgeryPose"]]
    with Server(rig, port=0) as server:
        (tmp_path / "job.json").write_text(json.dumps({"url": server.url, "steps": steps}))
        run = subprocess.run([threejs["node"], str(threejs["js"] / "serve_page.mjs"), str(tmp_path / "job.json"),
                              str(tmp_path / "out.json")], capture_output=True, text=True, timeout=120,
                             env={**os.environ, "CGASKIN_CHROMIUM": threejs["chromium"]})
    assert run.returncode == 0, run.stderr[-3000:]
    record = json.loads((tmp_path / "out.json").read_text())
    assert record["errors"] == [], record["errors"]
    shown = np.frombuffer(__import__("base64").b64decode(record["results"][-2]), np.float64).reshape(-1, 3)
    sent = record["results"][-1]["dilations"]
    # which of the model's joints the page scaled by which factor: the assignment whose skinning it shows
    diagonal = float(np.linalg.norm(np.ptp(rig.vertices, axis=0)))
    matches = []
    for first, second in (("arm.1", "arm1"), ("arm1", "arm.1")):
        pose = rig.pose(clip, 0.0).dilate(first, FACTORS["arm1"]).dilate(second, FACTORS["arm1_1"])
        if np.abs(cgaskin.skin(rig, pose) - shown).max() < 1e-4 * diagonal:
            matches.append({first: FACTORS["arm1"], second: FACTORS["arm1_1"]})
    assert len(matches) == 1, "the page's skinning matches neither assignment of its bones to the joints"
    assert sent == matches[0], (sent, matches[0])
