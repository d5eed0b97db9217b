"""
Drill a walled hole
===================

``cgaskin.drill`` removes what a drill bit sweeps: the solid within ``radius`` of the segment from
``start`` to ``end`` (a round tip). Where the bit passes inside the model, the hole gets a wall on
the bit's surface, from the entry to the exit (a hole through), or down to a round bottom (a blind
hole), so a closed model stays closed. Like a cut, a drill can happen in a pose; the new vertices
are skinned with the weights of the surface they were made on, so the hole animates.
"""
import numpy as np

import cgaskin
from cgaskin.app.render import render_strip

rig = cgaskin.capsule_arm()
through = cgaskin.drill_details(rig, [0.5, 0.0, -1.0], [0.5, 0.0, 1.0], radius=0.12)
print("through the upper arm:", through.wall_faces, "wall faces,", through.open_rims, "open rims")

# %%
# A blind hole into the forearm while the elbow is bent: the bit stops short of the axis.
bent = rig.rest_pose().rotate("elbow", [0, 0, 1], np.radians(50))
forearm = (bent.global_matrices()[1] @ [0.5, 0.0, 0.0, 1.0])[:3]             # half way down the forearm
blind = cgaskin.drill_details(through.rig, forearm + [0.0, 0.0, -1.0], forearm + [0.0, 0.0, 0.02], 0.1, pose=bent)
drilled = blind.rig

wall = np.zeros(drilled.n_faces, bool)
wall[drilled.n_faces - blind.wall_faces:] = True                   # the blind hole's wall and bottom
frames = [(cgaskin.skin(drilled, pose), drilled.faces, wall)
          for pose in (bent, drilled.rest_pose(), drilled.pose("wave", 1.0))]
render_strip(frames, "drill.png", titles=["drilled (blind hole bent)", "elbow straight", "clip 'wave' at 1 s"],
             elev=-70.0, columns=3, size=3.5)

# %%
# The model is still closed: its topology, welded by position (the hole's wall has vertices of its
# own, for its normals), has no boundary edge.
topology = cgaskin.rig_topology(drilled)
print(topology.n_edges, "edges,", len(topology.boundary_edges), "on a boundary")
