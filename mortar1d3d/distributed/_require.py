"""The optional packages of the distributed path, imported on demand with an error that names them."""
import importlib

from ..errors import MissingPackageError

#: what each optional package is for, and how it is installed (docs/distributed.md)
PACKAGES = {
    "mpi4py": "MPI from Python (pip install mpi4py, built against the MPI that PETSc uses)",
    "petsc4py": "PETSc's distributed matrices, vectors and solvers (PETSC_DIR=... pip install petsc4py "
                "matching the PETSc version)",
    "pymetis": "the METIS graph partition (pip install pymetis)",
}


def require(name, what='analysis.backend = "petsc"'):
    """Import ``name`` (one of :data:`PACKAGES`), or raise :class:`MissingPackageError` naming it."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        raise MissingPackageError(
            f"{what} needs the package {name!r}, which is not installed ({exc}): {PACKAGES[name]}; "
            "all of them: pip install \"mortar1d3d[mpi]\" with PETSC_DIR set to your PETSc (docs/distributed.md)"
        ) from None


def available():
    """True when every optional package of the distributed path imports."""
    try:
        for name in PACKAGES:
            importlib.import_module(name)
    except ImportError:
        return False
    return True
