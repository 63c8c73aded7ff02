"""Nonlinear (Newton) and linear (direct, AMG, block-preconditioned) solvers."""
