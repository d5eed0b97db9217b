"""Tests of cgaskin.animation: rig, clips, poses, skinning, mesh checks."""
