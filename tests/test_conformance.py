"""The conformance table's script (benchmarks/conformance.py): input folders, the listing of 4C's
files not run here, and the 4C files beyond the usual twenty where an input folder holds them
(``MORTAR1D3D_4C_INPUTS``, folders separated by ``os.pathsep``; skipped with the reason otherwise)."""
import importlib.util
import os
import warnings
from pathlib import Path

import pytest

from mortar1d3d.io import fourc
from mortar1d3d.io.fourc import FourCError

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("conformance", ROOT / "benchmarks" / "conformance.py")
conformance = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(conformance)

R = conformance.R


def extra_file(stem):
    """The path of 4C's file ``stem`` in one of the input folders; skips the test (with the reason)
    where no folder holds it."""
    for folder in conformance.input_folders(ROOT):
        path = Path(folder) / (stem + ".4C.yaml")
        if path.is_file():
            return path
    pytest.skip(f"4C's {stem}.4C.yaml is in no input folder: name its folder in {fourc.ENV_VAR} "
                f"(folders separated by {os.pathsep!r})")


def test_input_folders_split_the_variable(tmp_path, monkeypatch):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    monkeypatch.setenv(fourc.ENV_VAR, os.pathsep.join([str(a), str(tmp_path / "absent"), str(b)]))
    assert conformance.input_folders(ROOT) == [a, b]
    assert fourc.input_folder() == a              # the reader's tests take the first one
    (a / "x.4C.yaml").write_text("")
    (b / "x.4C.yaml").write_text("")
    (b / "y.4C.yaml").write_text("")
    assert conformance.input_files([a, b]) == [a / "x.4C.yaml", b / "y.4C.yaml"]
    monkeypatch.setenv(fourc.ENV_VAR, str(tmp_path / "absent"))
    assert conformance.input_folders(ROOT) == []
    assert fourc.input_folder() is None
    # a missing first folder does not hide the next one from the reader's tests
    monkeypatch.setenv(fourc.ENV_VAR, os.pathsep.join([str(tmp_path / "absent"), str(b)]))
    assert fourc.input_folder() == b and fourc.input_folders() == conformance.input_folders(ROOT) == [b]


def test_every_file_of_the_data_table_is_listed(tmp_path):
    """With no 4C file given, every file of NOT_HERE appears in the page's "not run here" section
    with what it needs; a file that is given drops out of that section."""
    out = tmp_path / "conformance.md"
    conformance.write([], out, conformance.not_here([]))
    text = out.read_text(encoding="utf-8")
    section = text[text.index("## 4C files not run here"):]
    assert len(conformance.NOT_HERE) == 29
    for stem, feature in conformance.NOT_HERE.items():
        line = next(ln for ln in section.splitlines() if f"`{conformance.short(stem + '.4C.yaml')}`" in ln)
        assert (feature or "none known") in line
    given = R + "beam_in_solid_column_segmentation.4C.yaml"
    assert (R + "beam_in_solid_column_segmentation", None) not in conformance.not_here([Path(given)])
    assert len(conformance.not_here([Path(given)])) == 28


@pytest.mark.parametrize("stem", ["beam_in_solid_column_segmentation", "beam_along_solid_boundary_segmentation"])
def test_segmentation_files_pass(stem):
    """4C's Gauss-point-to-segment files with segmentation (BEAM3R HERMITE, hex8 column, penalty)
    reproduce 4C's six displacement values to its tolerance 1e-8."""
    path = extra_file(R + stem)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = fourc.check(path)
    assert report.passed
    assert len(report.rows) == 6
    assert report.max_deviation < 1e-12


@pytest.mark.parametrize("triad, bound", [("deformation_gradient_y_2d", 1e-12), ("deformation_gradient_z_2d", 2e-12),
                                          ("deformation_gradient_average_2d", 5e-12)])
def test_plane_rotation_triads_pass(triad, bound):
    """The plane rotational-coupling variants of the polar_decomposition_2d file (the library's
    plane_y, plane_z and plane_average triads) reproduce 4C (tolerance 1e-10; measured 2.9e-13,
    5.2e-13 and 1.1e-12)."""
    path = extra_file(R + "rotational_coupling_gpts_" + triad)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = fourc.check(path)
    assert report.passed and report.max_deviation < bound


@pytest.mark.parametrize("name, bound", [
    ("rotational_coupling_mortar_line4_line3_deformation_gradient_average_2d", 1e-13),
    ("rotational_coupling_mortar_line4_line3_deformation_gradient_3d_local_1", 1e-14),
    ("rotational_coupling_mortar_line2_line2_deformation_gradient_3d_local_1", 1e-14)])
def test_mortar_rotational_triads_pass(name, bound):
    """Mortar rotational coupling with the plane average triad and 4C's 3d_local_1 triad (the
    library's deformation_gradient_local_1) reproduce 4C to round-off (measured 8.9e-15, 7.4e-16,
    3.6e-16; tolerance 1e-10)."""
    path = extra_file(R + name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report = fourc.check(path)
    assert report.passed and report.max_deviation < bound


def test_fix_triad_2d_is_named_as_missing():
    """4C's fix_triad_2d couples the beam to two solid triads at once (the y and the z one): not
    built, so the reader stops with the key and the value."""
    path = extra_file(R + "rotational_coupling_gpts_fix_triad_2d")
    with pytest.raises(FourCError, match="ROTATION_COUPLING: 'fix_triad_2d' is not supported"):
        fourc.scene_from_4c(path)


def test_several_coupling_conditions_are_refused(tmp_path):
    """4C ties each beam line set only to the solid volumes of its COUPLING_ID (its `conditions`
    file); the reader ties every beam to the whole solid, so it refuses a second condition instead
    of solving another problem."""
    folder = fourc.input_folder()
    if folder is None:
        pytest.skip(f"no 4C input files: set {fourc.ENV_VAR} or provide shared/4c-inputs beside the "
                    "repository's folder")
    source = folder / (R + "beam_in_solid_column_gauss_point_projection_boundary_segmentation.4C.yaml")
    text = source.read_text(encoding="utf-8")
    one = "BEAM INTERACTION/BEAM TO SOLID VOLUME MESHTYING LINE:\n  - E: 1\n    COUPLING_ID: 1\n"
    assert one in text
    fourc.scene_from_4c(source)                   # as 4C wrote it: one condition, read
    path = tmp_path / source.name
    path.write_text(text.replace(one, one + "  - E: 1\n    COUPLING_ID: 2\n"), encoding="utf-8")
    with pytest.raises(FourCError, match="MESHTYING LINE: 2 conditions"):
        fourc.scene_from_4c(path)
