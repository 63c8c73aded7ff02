"""One preconditioner for several linear solves: a Newton loop keeps the AMG set-up of one
tangent for the next ones while they converge nearly as fast."""
from ._common import LinearSolverError

__all__ = ["ReusedPreconditioner", "REBUILD_GROWTH", "REBUILD_SLACK"]

#: a reused preconditioner is dropped (the next solve builds a new one) once a solve with it needs
#: more than ``REBUILD_GROWTH`` times the iterations of the solve that built it, plus
#: ``REBUILD_SLACK``: a set-up costs about as much as 10-20 iterations (benchmarks/README.md,
#: "Newton: reused preconditioner")
REBUILD_GROWTH = 1.5
#: iterations added to ``REBUILD_GROWTH`` times the first solve's before a set-up is rebuilt
REBUILD_SLACK = 5


class ReusedPreconditioner:
    """Keep the preconditioner of a solve for the following ones.

    ``solve(preconditioner)`` is a linear solve (:func:`~mortar1d3d.solvers.linear.solve_linear`
    or :func:`~mortar1d3d.solvers.saddle.solve_saddle` with all other arguments bound) returning
    a tuple whose last entry is its info dict; with ``preconditioner=None`` it builds one and
    reports it as ``info["preconditioner"]``.

    Attributes
    ----------
    builds, reuses : int
        Solves that built a preconditioner, and solves that used a kept one.

    Notes
    -----
    The preconditioner only changes the path to the solution, not the tolerance it is solved to:
    an AMG hierarchy of an earlier tangent is still symmetric positive definite (so CG and the
    block methods apply) and nearly as good while the tangent changes little (a few Newton
    iterations, small load steps). A solve with the kept preconditioner that does not converge,
    or breaks down and falls back to another method, is repeated with a new one; one that
    needed many more iterations than the solve that built it drops it for the next call.
    """

    def __init__(self):
        self.current = None
        self.iterations = 0
        self.builds = 0
        self.reuses = 0

    def clear(self):
        """Forget the kept preconditioner (its matrices can be large)."""
        self.current = None

    def solve(self, solve):
        if self.current is not None:
            try:
                out = solve(self.current)
            except LinearSolverError:
                out = None
            if out is not None and "fallback" not in out[-1]:
                info = out[-1]
                info.pop("preconditioner", None)
                info["reused"] = True
                self.reuses += 1
                if info["iterations"] > REBUILD_GROWTH * self.iterations + REBUILD_SLACK:
                    self.current = None
                return out
            self.current = None
        out = solve(None)
        info = out[-1]
        self.current = info.pop("preconditioner", None)
        self.iterations = info["iterations"]
        info["reused"] = False
        self.builds += 1
        return out
