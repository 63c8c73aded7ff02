"""Distributed assembly and solve on PETSc under MPI (``analysis.backend = "petsc"``; docs/distributed.md).

The optional extra ``mpi`` (mpi4py, petsc4py, pymetis) is imported only when a function here
needs it; without it, asking for the PETSc backend raises
:class:`~mortar1d3d.errors.MissingPackageError` naming the missing package.

* :mod:`.partition`: solid and beam elements to ranks (one graph; METIS or geometric slabs).
* :mod:`.numbering`: the rank-major numbering of nodes and multiplier nodes.
* :mod:`.assemble`: D, M, κ as PETSc ``MPIAIJ`` matrices and vectors from the unchanged serial kernels
  run per rank on its owned beam elements.
* :mod:`.system`: each rank's owned solid and beam elements evaluated into PETSc vectors and matrices.
* :mod:`.linear`: the Krylov solvers and preconditioners (the auxiliary-space sweep of :mod:`.auxiliary`
  by default for penalty systems; GAMG with rigid-body modes, MUMPS, a Schur field split).
* :mod:`.solve`: a scene on PETSc: partition, coupling, the library's Newton loop or linear step, the
  Result on rank 0.
* :mod:`.output`: every rank's elements as parallel VTU pieces.
"""
from ._require import MissingPackageError, available, require
from .partition import Partition, partition

__all__ = ["MissingPackageError", "Partition", "available", "partition", "require"]
