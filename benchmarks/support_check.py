"""Cost of the zero-energy-mode check (``Model.check_zero_energy_modes``) on ``fibre_cube(20, 1000, 20)``.

    .venv/bin/python benchmarks/support_check.py [--repeats 5]

The scene of ``penalty_solve.py`` (1000 straight torsion-free fibres of 20 elements, mortar penalty
coupling, linear): prints the median wall time of the check, of ``assemble_mortar`` and of the whole
``Model.prepare`` (which runs the check once), and the load average (a shared machine is noisy).
"""
import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))     # measure this checkout's package

import mortar1d3d as m13  # noqa: E402
from mortar1d3d.model import Model  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    beams, solid = m13.generate.fibre_cube(20, 1000, 20)
    scene = m13.Scene(solid={"mesh": solid, "material": {"model": "linear_elastic", "E": 1e9, "nu": 0.3}},
                      beams=[{"mesh": beams, "section": {"E": 2e11, "radius": 0.003}}],
                      dirichlet=[{"on": "solid:x_min"}], analysis={"kinematics": "linear", "solver": "amg"})
    model = Model(scene).prepare()          # compiles (or loads) every kernel once
    m13.assemble_mortar(beams, solid)
    check, assembly, prepare = [], [], []
    for _ in range(args.repeats):
        t = time.perf_counter()
        model.check_zero_energy_modes()
        check.append(time.perf_counter() - t)
        t = time.perf_counter()
        m13.assemble_mortar(beams, solid)
        assembly.append(time.perf_counter() - t)
        t = time.perf_counter()
        Model(scene).prepare()
        prepare.append(time.perf_counter() - t)
    c, a, p = (statistics.median(x) for x in (check, assembly, prepare))
    print(f"zero-energy check {c * 1e3:.0f} ms, assemble_mortar {a * 1e3:.0f} ms, Model.prepare (with the check) "
          f"{p * 1e3:.0f} ms: the check is {c / a:.2f}x the assembly, {c / p:.2f} of prepare "
          f"(medians of {args.repeats}; load average {os.getloadavg()[0]:.1f})")


if __name__ == "__main__":
    main()
