"""Tests of cgaskin.surgery: topology, BVH, cut and tear."""
