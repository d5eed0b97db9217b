"""
Cut a posed model and re-pose the halves
========================================

``cgaskin.cut`` splits a rig by a plane. Given the pose the model is shown in, the plane cuts the
*posed* mesh: every new vertex lands on the plane in that pose, and is placed back in rest space
(through its blended bone transform), so both halves are rigs again, with the skeleton, weights and
clips of the original. ``cap=True`` closes each half's cut with a planar cap.
"""
import numpy as np

import cgaskin
from cgaskin.app.render import render_strip

rig = cgaskin.capsule_arm()
bent = rig.rest_pose().rotate("elbow", [0, 0, 1], np.radians(50))

# across the middle of the forearm, in the bent pose, tilted so that the cap is an ellipse
joints = bent.global_matrices()[:, :3, 3]
elbow, wrist = joints[1], joints[2]
normal = (elbow - wrist) + np.array([0.0, 0.0, 0.3])
upper, lower = cgaskin.cut(rig, normal, (elbow + wrist) / 2, pose=bent, cap=True)
print("upper:", upper.n_vertices, "vertices; lower:", lower.n_vertices, "vertices")

# %%
# The halves pose like the original: here in the pose they were cut in, then with the elbow bent the
# other way and the wrist dilated, then from the clip.
again = bent.rotate("elbow", [0, 0, 1], np.radians(-80)).dilate("wrist", 1.4)
frames, titles = [], []
for name, half in (("upper", upper), ("lower", lower)):
    for label, pose in (("as cut", bent), ("re-posed, wrist x1.4", again), ("clip 'wave' at 1 s", half.pose("wave", 1.0))):
        frames.append((cgaskin.skin(half, pose), half.faces))
        titles.append(f"{name} half, {label}")
render_strip(frames, "cut.png", titles=titles, columns=3, size=3.0)

# %%
# ``cut_details`` tells more: the input vertex of each output vertex, the new vertices made on crossed
# edges, and ``residual``, how far a new vertex skinned in the pose it was cut in lies from where it
# was made on the plane (rounding only).
details = cgaskin.cut_details(rig, normal, (elbow + wrist) / 2, pose=bent, cap=True)
print(len(details.new_positions), "new vertices on crossed edges; residual", details.residual)
