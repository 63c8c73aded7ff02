"""The trade-off study's building blocks and a tiny report (mortar1d3d.study, issue 5).

The reference rule of the study (segment-based with a high Gauss count) is checked against an
independent adaptive quadrature; error measures against hand-made differences; the tiny report
through the command line (tables, plots, sentences, and numbers in sane ranges). No timing is
asserted: times are only required to be positive.
"""
import json
import math

import numpy as np
import pytest

import mortar1d3d as m13
from mortar1d3d import study
from mortar1d3d.cli import main


@pytest.mark.parametrize("kind", ["straight fibres, hex8", "curved fibres, hex27", "curved fibres, tet10"])
def test_reference_rule_matches_adaptive_quadrature(kind):
    beams, solid = study.build_scene(kind, 2.0, "partly outside", cells=4, fibres=3, seed=5)
    ops = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=4)
    cuts = np.bincount(ops.segments["beam_element"], minlength=beams.n_elements)
    chosen = np.argsort(-cuts, kind="stable")[:2]
    assert cuts[chosen].min() >= 2                      # elements that cross faces
    check = study.pair_reference_check(beams, solid, chosen, n_gauss=16)
    assert check["segments"] >= 4
    assert check["face"] < 1e-10                       # interior segment ends lie on faces
    for name in ("D", "M", "kappa"):
        assert check[name] < 1e-11, (name, check)
    # too few points for curved geometry is caught by the same comparison
    if kind != "straight fibres, hex8":
        assert max(study.pair_reference_check(beams, solid, chosen, n_gauss=1)[k] for k in ("D", "M")) > 1e-5


def test_adaptive_integrals_of_a_straight_segment_by_hand():
    # straight beam (0,0,0)-(1,0,0) in the cell [0,1]^3: κ = ∫ Φ_j ds = 1/2 each, D of line2 = [[1/3, ...]]
    solid = m13.generate.box((0, 0, 0), (1, 1, 1), (1, 1, 1), "hexahedron")
    beams = m13.BeamMesh.hermite(np.array([[0.0, 0.5, 0.5], [1.0, 0.5, 0.5]]), np.array([[1.0, 0, 0]] * 2),
                                 np.array([[0, 1]]))
    kappa, D, M = study.adaptive_segment_integrals(beams, solid, 0, 0, -1.0, 1.0)
    np.testing.assert_allclose(kappa, [0.5, 0.5], rtol=1e-13)
    # ∫ Φ_1 H_1 ds with Φ_1 = (1-η)/2, H_1 = (2-3η+η³)/4, ds = dη/2: 7/20
    assert D[0, 0] == pytest.approx(7 / 20, rel=1e-13)
    # partition of unity of the solid functions: Σ_a M[0, a] = κ_0
    assert M[0].sum() == pytest.approx(0.5, rel=1e-13)


def test_operator_errors():
    beams, solid = m13.generate.fibre_cube(3, 2, 3)
    ref = m13.assemble_mortar(beams, solid, integration="segment", n_gauss=8)
    same = study.operator_errors(ref, ref)
    assert all(v == 0.0 for v in same.values())
    coarse = m13.assemble_mortar(beams, solid, integration="element", n_gauss=2)
    err = study.operator_errors(coarse, ref)
    dM = (coarse.M - ref.M).toarray()
    assert err["M_fro"] == pytest.approx(np.linalg.norm(dM) / np.linalg.norm(ref.M.toarray()), rel=1e-12)
    assert err["M_max"] == pytest.approx(np.abs(dM).max() / np.abs(ref.M.toarray()).max(), rel=1e-12)
    assert 1e-6 < err["M_fro"] < 1


def test_scenes_have_the_requested_size_ratio_and_embedding():
    for ratio, per_fibre in ((0.25, 12), (1.0, 3), (4.0, 1)):
        beams, solid = study.build_scene("straight fibres, hex8", ratio, "embedded", cells=6, fibres=3)
        assert beams.n_elements == 3 * per_fibre
    inside = m13.assemble_mortar(*study.build_scene("curved fibres, tet10", 1.0, "embedded", cells=3, fibres=3),
                                 integration="segment")
    assert inside.embedded_length == pytest.approx(inside.beam_length, rel=1e-9)
    outside = m13.assemble_mortar(*study.build_scene("curved fibres, tet10", 1.0, "partly outside", cells=3,
                                                     fibres=3), integration="segment")
    assert 0.2 < outside.embedded_length / outside.beam_length < 0.8


def test_solution_monitor_is_a_marked_hook():
    with pytest.raises(NotImplementedError, match="linear"):
        study.solution_monitor(None, None, None, None)


def test_tiny_report_through_the_command_line(tmp_path):
    pytest.importorskip("matplotlib")
    out = tmp_path / "report"
    assert main(["bench", "report", "--tiny", "--quiet", "--out", str(out)]) == 0
    text = (out / "accuracy_vs_time.md").read_text()
    for png in ("pareto.png", "stages.png", "scaling.png"):
        assert (out / png).stat().st_size > 5000
        assert f"]({png})" in text
    for heading in ("## Findings", "## The reference", "## Tables", "## Scaling", "## Start-up",
                    "\"auto\" on the benchmark scene"):
        assert heading in text
    assert "To reach a D/M error of 1e-08 on straight fibres, hex8" in text
    assert "not measured yet" in text                   # the solution error is an honest gap
    results = json.loads((out / "results.json").read_text())
    assert len(results["scenes"]) == 4
    for scene in results["scenes"]:
        records = {(r["integration"], r["n_gauss"]): r for r in scene["records"]}
        assert all(r["time_s"] > 0 and r["points"] > 0 for r in records.values())
        assert scene["reference_vs_coarser"] < 1e-8
        # 1 point per beam element misses every kink: a large error
        assert records[("element", 1)]["M_fro"] > 1e-3
        # straight fibres in hex8: segment-based with 4 points and auto are exact
        if scene["kind"].startswith("straight"):
            assert records[("segment", 4)]["M_fro"] < 1e-13
            assert max(records[("auto", 2)]["D_fro"], records[("auto", 2)]["M_fro"]) < 1e-13
        else:   # curved: auto = segment-based with the same n
            assert records[("auto", 2)]["M_fro"] == pytest.approx(records[("segment", 2)]["M_fro"], rel=1e-6)
    for check in results["reference_checks"].values():
        assert max(check["D"], check["M"], check["kappa"]) < 1e-11
    target = results["auto_target"]
    assert target["auto"]["M_fro"] < 1e-13 and target["element"]["M_fro"] > 1e-6
    assert target["auto_over_element"] > 0 and math.isfinite(target["auto_over_element"])
    assert [r["points"] for r in results["scaling"]["rows"]] == sorted(r["points"] for r in results["scaling"]["rows"])
    assert results["startup"]["warm"]["in_process_s"] > 0
