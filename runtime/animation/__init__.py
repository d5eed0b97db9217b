"""The animation layer: the rig data model, clips, poses and skinning."""
