"""Asking for the PETSc backend without the mpi extra: an error that names the missing package
(runs with and without the extra: the packages are hidden from the import system)."""
import importlib
import sys

import pytest

import mortar1d3d as m13
from mortar1d3d.cli import main
from mortar1d3d.distributed import MissingPackageError
from mortar1d3d.scene import SceneError

ORDER = ("mpi4py", "petsc4py", "pymetis")     # the order in which solve() asks for them


def _importable(name):
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


def _scene(backend="petsc"):
    return m13.Scene(solid={"mesh": {"box": [[0, 0, 0], [1, 1, 1]], "cells": [1, 1, 1]},
                            "material": {"model": "linear_elastic", "E": 1.0, "nu": 0.3}},
                     dirichlet=[{"on": "solid:x_min", "value": [0, 0, 0]}],
                     analysis={"kinematics": "linear", "backend": backend})


@pytest.mark.parametrize("missing", ["mpi4py", "petsc4py", "pymetis"])
def test_petsc_backend_without_the_extra_names_the_package(monkeypatch, missing):
    # the first package missing is named: this one, or one before it that is not installed here
    named = next(n for n in ORDER if n == missing or not _importable(n))
    monkeypatch.setitem(sys.modules, missing, None)       # import of it fails, as when not installed
    with pytest.raises(MissingPackageError, match=rf"analysis.backend = \"petsc\" needs the package '{named}'.*"
                                                  r"pip install \"mortar1d3d\[mpi\]\""):
        m13.solve(_scene())


def test_command_line_reports_the_missing_package(monkeypatch, tmp_path, capsys):
    # petsc4py hidden; without the extra mpi4py, asked for first, is the one named
    named = next(n for n in ORDER if n == "petsc4py" or not _importable(n))
    monkeypatch.setitem(sys.modules, "petsc4py", None)
    path = tmp_path / "scene.toml"
    path.write_text('[solid]\nmesh = { box = [[0, 0, 0], [1, 1, 1]], cells = [1, 1, 1] }\n'
                    'material = { model = "linear_elastic", E = 1.0, nu = 0.3 }\n'
                    '[[dirichlet]]\non = "solid:x_min"\nvalue = [0, 0, 0]\n'
                    '[analysis]\nkinematics = "linear"\nbackend = "petsc"\n')
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert f"needs the package '{named}'" in capsys.readouterr().err


def test_unknown_backend_is_a_scene_error():
    with pytest.raises(SceneError, match=r"analysis.backend"):
        _scene("cuda")


def test_an_indefinite_sweep_names_what_to_do():
    """The error of a penalty solve whose auxiliary-space sweep became indefinite (PETSc's reason -8)
    names the option that makes it possible (-mortar_beam_blocks rank: the beam solve on the ranks'
    owned beam unknowns) and the PETSc options that avoid it; other reasons and methods get no such hint."""
    from mortar1d3d.distributed.linear import DIVERGED_INDEFINITE_PC, divergence_hint
    hint = divergence_hint("aux", DIVERGED_INDEFINITE_PC)
    assert "-mortar_beam_pc_type lu -mortar_beam_pc_factor_mat_solver_type mumps" in hint
    assert "-mortar_penalty_pc gamg" in hint and "three or more ranks" in hint
    assert "-mortar_beam_blocks rank" in hint
    assert divergence_hint("aux", -3) == ""                  # KSP_DIVERGED_ITS: nothing specific
    assert divergence_hint("gamg", DIVERGED_INDEFINITE_PC) == ""


@pytest.mark.parametrize("environ, ranks", [({}, 1), ({"OMPI_COMM_WORLD_SIZE": "4"}, 4), ({"PMI_SIZE": "3"}, 3),
                                            ({"MV2_COMM_WORLD_SIZE": "2"}, 2), ({"PMI_SIZE": ""}, 1)])
def test_launched_ranks_read_from_the_launcher_environment(environ, ranks):
    from mortar1d3d.cli import launched_ranks
    assert launched_ranks(environ) == ranks


def test_a_serial_run_under_mpiexec_stops_instead_of_solving_once_per_process(monkeypatch, tmp_path, capsys):
    """Under ``mpiexec -n 2`` a serial scene would be solved by both processes, which would write the
    same files: the command refuses it naming the key, and --backend overrides the scene's."""
    path = tmp_path / "scene.toml"
    path.write_text('[solid]\nmesh = { box = [[0, 0, 0], [1, 1, 1]], cells = [1, 1, 1] }\n'
                    'material = { model = "linear_elastic", E = 1.0, nu = 0.3 }\n'
                    '[[dirichlet]]\non = "solid:x_min"\nvalue = [0, 0, 0]\n'
                    '[analysis]\nkinematics = "linear"\n')
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert 'analysis.backend = "serial" under an MPI launcher with 2 processes' in err
    assert not (tmp_path / "out").exists()
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--backend", "serial"]) == 2
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "1")
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--backend", "serial"]) == 0
    assert (tmp_path / "out" / "result.pvd").exists()
