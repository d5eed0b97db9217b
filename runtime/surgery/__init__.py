"""The surgery layer: welded topology, BVH, new vertices, and the cut and tear operations."""
