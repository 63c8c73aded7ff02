"""Geometry of the coupling, in pipeline order.

search (candidate pairs) -> context (the kernel context) -> segmentation, auto_segments (segments);
projection, intersection, beam and linalg are the kernels they share.
"""
