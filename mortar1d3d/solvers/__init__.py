"""Solvers: linear (direct, AMG, saddle-point block preconditioning); Newton comes later."""
from .linear import (LinearSolverError, build_amg, rigid_body_modes, solve_linear,
                     solve_saddle)

__all__ = ["LinearSolverError", "build_amg", "rigid_body_modes", "solve_linear", "solve_saddle"]
