"""
The viewer page
===============

``cgaskin.show(rig)`` makes the viewer: one self-contained HTML page (three.js and the model inside)
that opens from a file in any browser, without a network or a server. It plays the clips, orbits,
shows the skeleton with each bone's name, colours the vertices by a joint's weight, dilates a joint
live, and draws the open edges (cut rims, slits, holes) as lines that follow the skinning. In a
notebook the object shows itself inline; ``save`` writes the page. ``cgaskin view MODEL --out
PAGE.html`` is the same from the command line.

Pictures that headless Chromium took of such pages (the tests in ``tests/clients`` open them so):
the Fox model walking, and the head's weights with the skeleton shown.

.. image:: /view/view_fox_walk.png
   :width: 45%

.. image:: /view/view_fox_weights.png
   :width: 45%
"""
# sphinx_gallery_thumbnail_path = "view/view_fox_walk.png"
import numpy as np

import cgaskin

rig = cgaskin.capsule_arm()
torn = cgaskin.tear(rig, ([0.6, 0.05, 1.0], [0.6, 0.05, 0.0]), ([1.8, 0.05, 1.0], [1.8, 0.05, 0.0]), opening=0.06)
view = cgaskin.show(torn, clip="wave")
print(view)
view.save("capsule_arm_torn.html")

# %%
# A pose instead of a clip: the page holds it as an extra still clip named "pose", paused.
bent = torn.rest_pose().rotate("elbow", [0, 0, 1], np.radians(60)).dilate("wrist", 1.5)
cgaskin.show(torn, pose=bent).save("capsule_arm_bent.html")

# %%
# ``cgaskin serve MODEL`` serves the same page with a surgery panel: tear, cut and drill the playing
# model with the pointer, while Python does the surgery. A drag across Fox while it walks:
#
# .. image:: /view/serve_fox_tear.gif
#    :width: 60%
