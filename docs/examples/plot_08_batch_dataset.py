"""
A dataset with ``cgaskin batch``
================================

``cgaskin batch SPEC.toml --out DIR`` (or ``cgaskin.batch.run``) makes many posed, cut, torn and
drilled variants of many models on Dask: every model x pose x time x operation x instance is an item,
one task. An item's id is a hash of what defines it, and its random draws come from that id, so the
same spec gives the same files with any number of workers, and a run keeps what an earlier run made.
This one is small and local: the capsule arm, two times of its clip with a random dilation of the
elbow, and two random drills and two random cuts of each.
"""
import tempfile
from pathlib import Path

from dask.distributed import Client

import cgaskin
import cgaskin.batch
from cgaskin.app.render import render_strip

folder = Path(tempfile.mkdtemp())
(folder / "models").mkdir()
cgaskin.save(cgaskin.capsule_arm(), folder / "models" / "arm.glb")
(folder / "spec.toml").write_text("""
seed = 7
[[models]]
path = "models/*.glb"
[[poses]]
clip = "wave"
times = [0.5, 1.0]
[poses.edits]
dilate = { joint = "elbow", range = [0.7, 1.4] }
[[operations]]
kind = "drill"
count = 2
radius = [0.06, 0.09]
[[operations]]
kind = "cut"
count = 2
cap = true
""")

# %%
# Run it on a Dask cluster in this process (``cgaskin batch`` starts a local cluster of worker
# processes, or joins one with ``--scheduler``).
with Client(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as client:
    manifest = cgaskin.batch.run(folder / "spec.toml", folder / "out", client=client)
print(manifest.computed, "items made,", len(manifest.errors), "failed")
table = manifest.table().to_pylist()
for row in table[:4]:
    print(row["pose"], row["operation"], row["files"], row["vertices"])

# %%
# Each output is a rig whose node transforms hold the item's pose, so its rest pose shows it posed.
frames, titles = [], []
for row in table[:6]:
    item = cgaskin.load(folder / "out" / row["files"][0])
    frames.append((cgaskin.skin(item, item.rest_pose()), item.faces))
    titles.append(f"{row['pose']} {row['operation']}")
render_strip(frames, "batch.png", titles=titles, columns=3, size=3.0)
