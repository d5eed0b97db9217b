"""
Dilation about a joint
======================

In CGA a uniform scale is a versor like a rotation or a translation: a *dilator*. A joint's local
transform is T R D, and ``pose.dilate(joint, s)`` scales the joint's part of the mesh (and every
part below it in the skeleton) by ``s`` about the joint itself, without any extra bookkeeping: the
dilator composes with the rotations and translations by the same geometric product.
"""
import numpy as np

import cgaskin
from cgaskin import versor
from cgaskin.app.render import render_strip

rig = cgaskin.capsule_arm()
rest = rig.rest_pose()
bent = rest.rotate("elbow", [0, 0, 1], np.radians(45))
poses = {
    "rest": rest,
    "elbow dilated x1.6": rest.dilate("elbow", 1.6),
    "elbow dilated x0.6": rest.dilate("elbow", 0.6),
    "bent 45 deg, then x1.6": bent.dilate("elbow", 1.6),
}
frames = [(cgaskin.skin(rig, pose), rig.faces) for pose in poses.values()]
render_strip(frames, "dilation.png", titles=list(poses), columns=4, size=3.0)

# %%
# The joint stays where it was: a dilator about the joint's own origin fixes the joint. The elbow's
# position (the translation of its global matrix) is the same in the rest pose and dilated.
elbow = rig.skeleton.names.index("elbow")
print(rest.global_matrices()[elbow][:3, 3], rest.dilate("elbow", 1.6).global_matrices()[elbow][:3, 3])

# %%
# The same algebra on plain arrays: ``versor.dilator(s)`` scales about the origin, ``compose`` is
# the geometric product (``compose(a, b)`` applies ``b`` first) and ``apply`` is the sandwich
# V X Ṽ on points. Scaling about a point p is T(p) D T(-p).
p = np.array([1.0, 0.0, 0.0])
about_p = versor.compose(versor.translator(p), versor.compose(versor.dilator(2.0), versor.translator(-p)))
print(versor.apply(about_p, [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]]))
