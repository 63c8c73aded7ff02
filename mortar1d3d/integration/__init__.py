"""Quadrature and integration points (element-based and segment-based)."""
