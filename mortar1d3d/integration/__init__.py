"""Integration points of the coupling integrals: segment-based, element-based and auto (points.py)."""
