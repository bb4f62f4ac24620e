"""Mapping kernels: BVH, per-image visibility, time tree, coverage, observation quality, stereo pairs."""
