"""Solvers: ``newton`` (load steps, step cutting) and ``linear`` (the linear solvers' entry points
``solve_linear`` and ``solve_saddle``), built from ``rigid`` (rigid-body modes), ``direct``
(SuperLU), ``amg`` (smoothed aggregation), ``preconditioners`` (auxiliary space), ``krylov``
(CG/MINRES/GMRES driver), ``dependent`` (dependent constraint rows), ``saddle`` (saddle point) and
``reuse`` (a preconditioner kept across Newton iterations).
Import the submodules; nothing heavy (scipy, pyamg) is imported here."""
