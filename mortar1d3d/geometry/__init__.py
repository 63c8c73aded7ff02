"""Geometry kernels: broad phase, projection into solid elements, beam-face intersection, segmentation."""
