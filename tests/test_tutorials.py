"""Every tutorial of examples/tutorials/ runs (at small sizes) and prints the numbers its page
states; each test fails if the tutorial's claim stops holding."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

TUTORIALS = Path(__file__).resolve().parent.parent / "examples" / "tutorials"


def _load(name):
    spec = importlib.util.spec_from_file_location(f"tutorial_{name}", TUTORIALS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_tutorial_has_a_test():
    scripts = sorted(p.stem for p in TUTORIALS.glob("t[0-9][0-9]_*.py"))
    tested = {name for name in globals() if name.startswith("test_t")}
    assert scripts and all(f"test_{s}" in tested for s in scripts), (scripts, tested)


def test_t01_operators_by_hand(capsys):
    out = _load("t01_operators_by_hand").run()
    printed = capsys.readouterr().out
    assert "largest difference to the hand values" in printed
    assert out["D_error"] < 1e-15 and out["M_error"] < 1e-15 and out["kappa_error"] < 1e-15
    assert out["M"][0, 0] == pytest.approx(1 / 8, abs=1e-15)
    assert out["D"][0, 1] == pytest.approx(1 / 20, abs=1e-15)
    assert out["embedded_length"] == pytest.approx(1.0, abs=1e-14)
    assert out["constraint_residual"] < 1e-14
    assert np.allclose(out["half_kappa"], [1 / 8, 3 / 8], atol=1e-15)
    assert out["half_embedded_length"] == pytest.approx(0.5, abs=1e-15)


def test_t02_element_vs_segment(capsys, tmp_path):
    out = _load("t02_element_vs_segment").run(gauss_counts=(2, 8, 32), out=tmp_path)
    printed = capsys.readouterr().out
    assert "element-based M, relative error" in printed and (tmp_path / "element_vs_segment.png").exists()
    # segment-based: three pieces, cut where the line crosses x = 1 and x = 2, exact to round-off
    assert out["segments"] == 3
    assert np.allclose(out["crossings"], [-5 / 14, 5 / 14], atol=1e-11)
    assert out["segment_vs_exact"] < 1e-15
    # element-based: far from exact and falling slowly (measured 2.46e-1, 1.62e-2, 4.68e-4)
    e = out["element_errors"]
    assert e[2] == pytest.approx(2.46e-1, rel=0.01) and e[8] == pytest.approx(1.62e-2, rel=0.01)
    assert e[2] > e[8] > e[32] > 1e-4


def test_t03_penalty_vs_lagrange(capsys, tmp_path):
    out = _load("t03_penalty_vs_lagrange").run(factors=(1e3, 1e4, 1e5), out=tmp_path)
    assert "log-log slope" in capsys.readouterr().out and (tmp_path / "penalty_vs_lagrange.png").exists()
    assert out["tip_deflection"] == pytest.approx(-6.509332e-02, rel=1e-5)
    e = out["errors"]
    # measured 1.409e-4, 1.497e-5, 1.506e-6: ten times the penalty, a tenth of the difference
    assert e[1e3] == pytest.approx(1.409e-4, rel=0.01) and e[1e5] == pytest.approx(1.506e-6, rel=0.01)
    assert -1.05 < out["slope"] < -0.95


def test_t04_reinforced_beam(capsys, tmp_path):
    out = _load("t04_reinforced_beam").run(out=tmp_path)
    assert "stiffening by the rebars" in capsys.readouterr().out
    assert (tmp_path / "reinforced_beam" / "result.pvd").exists()
    # measured: FE -1.196702e-3 / -1.102771e-3, theory -1.204385e-3 / -1.122016e-3
    assert out["plain"] == pytest.approx(-1.196702e-3, rel=1e-5)
    assert out["reinforced"] == pytest.approx(-1.102771e-3, rel=1e-5)
    assert out["theory_plain"] == pytest.approx(-1.204385e-3, rel=1e-6)
    assert abs(out["reinforced"] / out["theory_reinforced"] - 1) < 0.02
    assert out["stiffening"] == pytest.approx(1.0852, abs=1e-3) and out["theory_stiffening"] == pytest.approx(1.0734, abs=1e-3)
    assert out["coupled_length"] == pytest.approx(4.0, rel=1e-13)


def test_t05_own_solver(capsys):
    out = _load("t05_own_solver").run()
    assert "largest difference to mortar1d3d.solve" in capsys.readouterr().out
    # the hand-built solver with the library's D, M, κ reproduces the library's own solve
    # (measured 4.1e-11 penalty, 1.3e-12 Lagrange)
    assert out["penalty"]["difference"] < 1e-9 and out["lagrange"]["difference"] < 1e-10
    assert out["lagrange"]["tip"][2] == pytest.approx(-9.92493302e-04, rel=1e-7)
    assert out["D_shape"] == (33, 33) and out["M_shape"] == (33, 297)
