"""
An incision in strokes while the clip plays
===========================================

A ``cgaskin.Surgery`` is an editing session: each ``tear`` stroke extends the slit the previous one
made, and costs what it touches, not the whole mesh. Each stroke happens in a pose, here the clip's
pose at the time the stroke is made, as in ``cgaskin serve`` where the user drags a scalpel across a
playing model. A stroke is the blade (a segment: handle, tip) at the previous step and now, both in
the pose on screen.
"""
import numpy as np

import cgaskin
from cgaskin.app.render import render_strip

rig = cgaskin.capsule_arm()

# The blade stands across the skin on top of the arm (+z): handle above it, tip at the axis. It
# follows points fixed on the arm in rest space; to place it in a pose, its two ends are skinned with
# the weights of the nearest vertex, as the surface under them moves.
xs = np.linspace(0.5, 2.3, 10)
rest_blades = np.array([[[x, 0.05, 0.8], [x, 0.05, 0.0]] for x in xs])           # (steps, 2, 3)
nearest = np.abs(rig.vertices[None, :, 0] - xs[:, None]).argmin(axis=1)


def blade_in(pose, step):
    """The blade of ``step`` in ``pose``: its two ends skinned with the nearest vertex's weights."""
    joints = np.repeat(rig.joints[nearest[step]][None], 2, axis=0)
    weights = np.repeat(rig.weights[nearest[step]][None], 2, axis=0)
    ends = cgaskin.skin_affine(rest_blades[step], joints, weights, pose.bone_affines())
    return ends[0], ends[1]


surgery = cgaskin.Surgery(rig)
times = np.linspace(0.0, 0.9, len(xs))
for step in range(1, len(xs)):
    pose = rig.pose("wave", times[step])                   # the pose on screen when the stroke is made
    surgery.tear(blade_in(pose, step - 1), blade_in(pose, step), pose=pose, opening=0.04)
print(surgery.n_operations, "strokes;", surgery.n_vertices - rig.n_vertices, "new vertices;",
      "last stroke", surgery.last_cost)

# %%
# The session's rig is an immutable snapshot that animates like any other. The faces touching the
# new vertices (the slit's lips) are drawn blue.
torn = surgery.rig
lips = (torn.faces >= rig.n_vertices).any(axis=1)
frames = [(cgaskin.skin(torn, torn.pose("wave", t)), torn.faces, lips) for t in (0.0, 0.9, 1.6)]
render_strip(frames, "incision.png", titles=["'wave' at 0 s", "at 0.9 s (last stroke)", "at 1.6 s"],
             elev=60.0, columns=3, size=3.5)

# %%
# ``undo`` takes the last operation back exactly.
before = surgery.n_vertices
surgery.undo()
print(before, "->", surgery.n_vertices, "vertices after undo")
