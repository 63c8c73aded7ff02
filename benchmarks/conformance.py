"""Conformance with 4C: run every 4C input file of the input folders and write docs/conformance.md.

``make conformance`` (or ``python benchmarks/conformance.py [--out FILE] [FILES...]``) runs each
``*.4C.yaml`` of the folders of 4C's beam-to-solid volume meshtying regression inputs
(``$MORTAR1D3D_4C_INPUTS``, one folder or several separated by ``os.pathsep``; else
``shared/4c-inputs`` beside the repository's folder) with :func:`mortar1d3d.io.fourc.check` and
tabulates: whether it runs (or the feature it needs), whether every ``RESULT DESCRIPTION`` entry is
within 4C's tolerance, the largest deviation, 4C's tolerance, and the run time here (wall clock of
read + solve, warm kernel cache). 4C's other volume meshtying files, found in no folder, are listed
after the table with the feature each needs (:data:`NOT_HERE`), so that the page names every file.
"""
import argparse
import os
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

PREFIXES = {"beam3eb_static_beam_to_solid_volume_meshtying_": "EB_",
            "beam3r_herm2line3_static_beam_to_solid_volume_meshtying_": "R_"}


EB = "beam3eb_static_beam_to_solid_volume_meshtying_"
R = "beam3r_herm2line3_static_beam_to_solid_volume_meshtying_"
RESTART = "restart (4C runs `_first`, then `_second` from its restart files)"
CROSS_SECTION = "cross-section surface points (2D-3D coupling: `gauss_point_cross_section`)"

# 4C's beam-to-solid volume meshtying input files (its tests/list_of_tests.cmake and tests/input_files)
# that are not among the folder's usual twenty: file stem → what the library lacks to run it, as read
# from the file's parameter sections (or its name and its test entry where the file was not read);
# None: nothing known to be missing, the file only has to be given in an input folder. A file
# found in a folder runs in the table instead, whatever this says.
NOT_HERE = {
    EB + "beam_to_beam_contact": "beam-to-beam contact (`BEAM CONTACT`, penalty)",
    EB + "circ_curved_restart_first": RESTART,
    EB + "circ_curved_restart_second": RESTART,
    EB + "circ_restart_first": RESTART,
    EB + "circ_restart_second": RESTART,
    EB + "hex27_cross_section_projection_penalty_bending": CROSS_SECTION,
    EB + "hex27_cross_section_projection_penalty_patch": CROSS_SECTION,
    R + "2d-3d": CROSS_SECTION,
    R + "2d-3d_mortar": "cross-section coupling with mortar multipliers (full 2D-3D coupling)",
    R + "beam_along_solid_boundary_segmentation": None,
    R + "beam_in_solid_column_segmentation": None,
    R + "conditions": "several coupling conditions (`COUPLING_ID`: each beam tied to its own solid)",
    R + "gp_restart_first": RESTART,
    R + "gp_restart_second": RESTART,
    R + "mortar_restart_first": RESTART,
    R + "mortar_restart_second": RESTART,
    R + "mortar_lagrange_saddlepoint_dual_hermite": "dual Hermite multiplier shape functions "
                                                    "(`MORTAR_SHAPE_FUNCTION: dual_hermite`)",
    R + "rotational_coupling_circ": CROSS_SECTION + " with rotational coupling",
    **{R + f"rotational_coupling_gpts_deformation_gradient_3d_local_{k}":
       "4C's point-wise rotational force form in three dimensions (Gauss-point rotational coupling off the "
       "y-z plane; the triad itself is supported)" for k in (1, 2, 3)},
    R + "rotational_coupling_gpts_fix_triad_2d": "rotational coupling to two solid triads at once (`fix_triad_2d`: "
                                                 "the y and the z one)",
    **{R + f"rotational_coupling_gpts_deformation_gradient_{t}_2d": None for t in ("y", "z", "average")},
    R + "rotational_coupling_mortar_line2_line2_deformation_gradient_3d_local_1": None,
    R + "rotational_coupling_mortar_line4_line3_deformation_gradient_3d_cross_section":
        "rotational coupling triad `deformation_gradient_3d_general_in_cross_section_plane`",
    R + "rotational_coupling_mortar_line4_line3_deformation_gradient_3d_local_1": None,
    R + "rotational_coupling_mortar_line4_line3_deformation_gradient_average_2d": None,
}


def input_folders(repository_root=ROOT):
    """The existing folders of ``$MORTAR1D3D_4C_INPUTS`` (``os.pathsep``-separated), else the shared
    one beside the repository (:func:`mortar1d3d.io.fourc.input_folders`)."""
    from mortar1d3d.io.fourc import input_folders as folders
    return folders(repository_root)


def input_files(folders):
    """Every ``*.4C.yaml`` of the folders, by name (a name found twice is taken from the first folder)."""
    files = {}
    for folder in folders:
        for path in sorted(Path(folder).glob("*.4C.yaml")):
            files.setdefault(path.name, path)
    return [files[name] for name in sorted(files)]


def not_here(files):
    """The rows of :data:`NOT_HERE` whose file is not among ``files``: (stem, feature or None)."""
    present = {Path(f).name.removesuffix(".4C.yaml") for f in files}
    return [(stem, NOT_HERE[stem]) for stem in sorted(NOT_HERE) if stem not in present]


def short(name):
    for prefix, tag in PREFIXES.items():
        if name.startswith(prefix):
            return tag + name[len(prefix):].removesuffix(".4C.yaml")
    return name.removesuffix(".4C.yaml")


def run_one(path):
    """One row of the table (a dict)."""
    from mortar1d3d.errors import ConvergenceError, MeshError, SceneError
    from mortar1d3d.io.fourc import check
    start = time.perf_counter()
    row = {"file": short(path.name), "runs": "no", "passes": "-", "deviation": "-", "tolerance": "-",
           "seconds": "-", "note": ""}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            report = check(path)
    except (SceneError, MeshError) as exc:
        row["note"] = str(exc).replace("|", "\\|")
        return row
    except ConvergenceError as exc:
        row.update(runs="yes", passes="no", note=f"did not converge: {exc}")
        return row
    seconds = time.perf_counter() - start
    compared = [r for r in report.rows if r.status != "not comparable"]
    special = len(report.rows) - len(compared)
    row.update(runs="yes", passes="yes" if report.passed else "**no**", seconds=f"{seconds:.1f}",
               deviation=f"{report.max_deviation:.1e}",
               tolerance=f"{min(r.entry.tolerance for r in compared):.0e}" if compared else "-",
               note=f"{len(compared)} values" + (f", {special} SPECIAL not comparable" if special else ""))
    coupling = report.result.scene.coupling if report.result.scene.coupled else {}
    if not report.passed and coupling.get("rotational") is not None:
        row["note"] += ("; run with 4C's rotational force form (coupling.rotational.forces = \"fourc\") and "
                        "BEAM3R's Lagrange virtual spins (see fourc.md, Rotational coupling)")
    if not report.passed and any(d.rational for d, _ in report.result.model.solid_mesh.blocks):
        row["note"] += "; NURBS27: run with 4C's rule for negative κ and BEAM3R's Lagrange virtual spins (see fourc.md, NURBS27)"
    if report.notes:
        row["note"] += "; " + "; ".join(report.notes).replace("|", "\\|")
    return row


def write(rows, out, missing=(), load=None):
    lines = ["# Conformance with 4C", "",
             "Generated by `make conformance` (`benchmarks/conformance.py`): every beam-to-solid volume meshtying "
             "input file of 4C in the input folders (the folders named by `MORTAR1D3D_4C_INPUTS`, separated by "
             "`os.pathsep`; see [Running 4C input files](fourc.md)), run with "
             "`mortar1d3d check`. *deviation*: the largest |computed − 4C| over the file's RESULT DESCRIPTION "
             "values (node displacements); *tolerance*: 4C's own (the smallest of the file's entries); *time*: "
             "read + solve here, wall clock in seconds on the development machine (2 shared cores, warm kernel "
             "cache). Prefixes: `EB_` = `beam3eb_static_beam_to_solid_volume_meshtying_`, `R_` = "
             "`beam3r_herm2line3_static_beam_to_solid_volume_meshtying_`.", "",
             "| file | runs | passes | deviation | tolerance | time (s) | note |", "|---|---|---|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| `{r['file']}` | {r['runs']} | {r['passes']} | {r['deviation']} | {r['tolerance']} | "
                     f"{r['seconds']} | {r['note']} |")
    passing = sum(r["passes"] == "yes" for r in rows)
    running = sum(r["runs"] == "yes" for r in rows)
    lines += ["", f"{len(rows)} files: {running} run, {passing} pass 4C's tolerances."]
    if load is not None:
        # the times depend on what else the shared machine runs: say how busy it was
        lines += ["", f"Load average (1 min) while the table was made: {load[0]:.1f} at the start, {load[1]:.1f} "
                      f"at the end, on {os.cpu_count()} cores."]
    if missing:
        lines += ["", "## 4C files not run here", "",
                  f"4C's other beam-to-solid volume meshtying input files ({len(missing)}), in none of the input "
                  "folders, with the feature the library lacks to run each (from the file's parameter "
                  "sections, or its name and 4C's test entry). *none known*: the file only has to be given "
                  "in an input folder.", "",
                  "| file | needs |", "|---|---|"]
        lines += [f"| `{short(stem + '.4C.yaml')}` | {feature or 'none known'} |" for stem, feature in missing]
    Path(out).write_text("\n".join(lines) + "\n", encoding="utf-8")


def main(argv=None):
    from mortar1d3d.io.fourc import ENV_VAR
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", help="input files (default: every *.4C.yaml of the input folders)")
    parser.add_argument("--out", default=str(ROOT / "docs" / "conformance.md"))
    args = parser.parse_args(argv)
    files = [Path(f) for f in args.files]
    missing = ()
    if not files:
        folders = input_folders(ROOT)
        if not folders:
            print(f"no 4C input folder: set {ENV_VAR} or provide shared/4c-inputs beside the repository's folder; "
                  "nothing regenerated")
            return 0
        files = input_files(folders)
        missing = not_here(files)
    rows = []
    load_start = os.getloadavg()[0]
    for path in files:
        row = run_one(path)
        print(f"{row['file']}: runs {row['runs']}, passes {row['passes']}, deviation {row['deviation']}, "
              f"time {row['seconds']} s {row['note'][:120]}", flush=True)
        rows.append(row)
    write(rows, args.out, missing, (load_start, os.getloadavg()[0]))
    print(f"wrote {args.out}: {len(rows)} files run, {len(missing)} listed as not run here")
    return 0


if __name__ == "__main__":
    sys.exit(main())
