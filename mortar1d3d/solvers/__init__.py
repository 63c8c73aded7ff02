"""Solvers: ``newton`` (load steps, step cutting) and ``linear`` (direct, AMG, saddle-point block
preconditioning). Import the submodules; nothing heavy (scipy, pyamg) is imported here."""
