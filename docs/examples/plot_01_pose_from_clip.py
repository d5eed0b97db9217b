"""
Load a model and pose it from a clip
====================================

A rig holds a mesh, a skeleton, skin weights and animation clips. Here the built-in capsule arm is
saved as a skinned glTF file and loaded back, as any ``.glb`` is; then its clip ``"wave"`` is
sampled at a few times, one frame at a time and as one batch, and every frame is skinned.
"""
import tempfile
from pathlib import Path

import numpy as np

import cgaskin
from cgaskin.app.render import render_strip

folder = Path(tempfile.mkdtemp())
cgaskin.save(cgaskin.capsule_arm(), folder / "arm.glb")
rig = cgaskin.load(folder / "arm.glb")
print(rig.n_vertices, "vertices,", rig.n_faces, "faces, joints", rig.skeleton.names)
print("clips:", [(clip.name, clip.duration) for clip in rig.clips])

# %%
# One pose per time: ``rig.pose(clip, time)`` samples the clip as glTF defines (a time past the last
# key holds the last key), ``cgaskin.skin`` moves every vertex by its joints' versors.
times = [0.0, 0.5, 1.0, 1.5]
frames = [(cgaskin.skin(rig, rig.pose("wave", t)), rig.faces) for t in times]
render_strip(frames, "wave.png", titles=[f"'wave' at {t} s" for t in times], columns=4, size=3.0)

# %%
# Many frames at once: ``rig.poses`` samples every time in one compiled call, and ``skin`` of a
# ``Poses`` returns every frame, shape (frames, vertices, 3). The frames are the same as one by one.
poses = rig.poses("wave", np.linspace(0.0, 2.0, 50))
batch = cgaskin.skin(rig, poses)
print(batch.shape, np.abs(batch[25] - cgaskin.skin(rig, poses[25])).max())
