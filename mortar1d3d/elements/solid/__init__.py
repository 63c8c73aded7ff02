"""Solid element types, one module each; ``dispatch`` registers them."""
