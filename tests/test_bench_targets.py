"""The speed-target table of benchmarks/targets.py, from given records (nothing is timed here):
the figures picked from each script's records, the curved types judged per round against the
distorted hex8 of the same round, the ratios and the verdicts, and the recorder itself."""
import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("targets", ROOT / "benchmarks" / "targets.py")
targets = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(targets)


def _newton(scene, rnd, element, segment):
    return {"kind": "newton_path", "scene": scene, "round": rnd, "element_gp_per_s": element,
            "segment_gp_per_s": segment}


RECORDS = [
    {"kind": "throughput", "distort": 0.1, "integration": "element", "gp_per_s_1thread": 1.2e6,
     "gp_per_s_1thread_best": 1.3e6, "per_control_1thread": 0.3, "control_1thread_s": 0.26,
     "of_claimed": 0.97, "claimed_speedup": 1.9},
    {"kind": "throughput", "distort": 0.1, "integration": "segment", "gp_per_s_1thread": 6.0e5,
     "gp_per_s_1thread_best": 6.2e5, "per_control_1thread": 0.9, "control_1thread_s": 0.26,
     "of_claimed": 0.95, "claimed_speedup": 1.9},
    {"kind": "throughput", "distort": 0.0, "integration": "element", "gp_per_s_1thread": 2.5e6,
     "gp_per_s_1thread_best": 2.6e6, "per_control_1thread": 0.12, "control_1thread_s": 0.26,
     "of_claimed": 0.93, "claimed_speedup": 1.8},
    # round 0: the machine was twice as slow for everything; round 1 normal
    _newton("hex8", 0, 6.0e5, 3.0e5), _newton("hex27", 0, 2.7e5, 1.5e5), _newton("tet10", 0, 3.6e5, 1.8e5),
    _newton("hex8", 1, 1.2e6, 6.0e5), _newton("hex27", 1, 6.0e5, 2.7e5), _newton("tet10", 1, 6.0e5, 3.6e5),
    {"kind": "cold_start", "what": "demo", "cold": {"cpu_s": 40.0, "wall_s": 45.0, "in_process_s": 44.0},
     "warm": None},
    {"kind": "cold_start", "what": "element", "cold": {"cpu_s": 64.0, "wall_s": 70.0, "in_process_s": 69.0},
     "warm": []},
    {"kind": "cold_start", "what": "first", "cold": {"cpu_s": 110.0, "wall_s": 120.0, "in_process_s": 119.0},
     "warm": [{"cpu_s": 2.0, "wall_s": 2.1, "in_process_s": 1.2}, {"cpu_s": 2.0, "wall_s": 2.1, "in_process_s": 1.6},
              {"cpu_s": 2.0, "wall_s": 2.1, "in_process_s": 1.3}]},
    {"kind": "penalty_solve", "n": 20, "solver": "solid", "unknowns": 27783, "cpu_s": 1.6, "iterations": 11,
     "cpu_per_solid": 1.0, "iterations_per_solid": 1.0, "peak_memory_gb": 1.0, "load": 1.0},
    {"kind": "penalty_solve", "n": 20, "solver": "aux1-0.02-0.001f", "unknowns": 47000, "cpu_s": 4.8,
     "iterations": 12, "cpu_per_solid": 3.0, "iterations_per_solid": 12 / 11, "peak_memory_gb": 1.6, "load": 1.0},
    {"kind": "lagrange_solve", "case": "15:155", "path": "penalty aux", "unknowns": 21750, "cpu_s": 1.8,
     "iterations": 21, "cpu_per_penalty": 1.0, "load": 1.0},
    {"kind": "lagrange_solve", "case": "15:155", "path": "lagrange gmres", "unknowns": 26865, "cpu_s": 2.2,
     "iterations": 26, "cpu_per_penalty": 2.2 / 1.8, "load": 1.0},
    {"kind": "scaling_assembly", "integration": "element", "points": [10000, 100000, 1000000],
     "per_control": [0.01, 0.1, 1.0], "slope": 1.0},
    {"kind": "scaling_newton", "enforcement": "penalty", "unknowns": [10000, 1000000], "per_control": [1, 110],
     "slope": 1.02},
]


def test_figures_and_verdicts():
    found = targets.figures(RECORDS)
    rows = {r["key"]: r for r in targets.table(found, {})}
    assert rows["hex8_element"]["figure"] == 1.2e6
    assert rows["hex8_element"]["ratio"] == pytest.approx(0.6)
    assert not rows["hex8_element"]["met"]
    assert rows["threads_element"]["figure"] == 0.93 and rows["threads_element"]["met"]
    # per round: hex27 element 0.45 and 0.5 -> median 0.475; segment 0.5 and 0.45
    assert rows["hex27_element"]["figure"] == pytest.approx(0.475)
    assert rows["tet10_element"]["figure"] == pytest.approx(0.55)      # 0.6 and 0.5
    assert rows["tet10_segment"]["figure"] == pytest.approx(0.6)       # 0.6 and 0.6
    assert rows["tet10_segment"]["met"] and not rows["hex27_element"]["met"]
    assert "nurbs27_element" not in rows                               # not run: no row, nothing invented
    assert rows["element_cold"]["figure"] == 64.0 and rows["element_cold"]["ratio"] == pytest.approx(8.0)
    assert rows["first_warm"]["figure"] == 1.3 and rows["first_warm"]["met"]        # the median of three
    assert "warmup_cold" not in rows
    assert rows["demo_cold"]["figure"] == 40.0 and rows["demo_cold"]["ratio"] == pytest.approx(1.6)
    assert rows["penalty_20_cpu"]["figure"] == 3.0 and not rows["penalty_20_cpu"]["met"]
    assert rows["penalty_20_its"]["met"]
    assert rows["lagrange_cpu"]["figure"] == pytest.approx(2.2 / 1.8) and rows["lagrange_cpu"]["met"]
    assert rows["slope_element"]["met"] and rows["slope_newton"]["met"]
    assert "slope_segment" not in rows


def test_a_round_without_hex8_is_not_compared():
    found = targets.figures([_newton("hex27", 0, 5e5, 2e5)])
    assert "hex27_element" not in found


def test_table_lines_name_every_measured_target():
    rows = targets.table(targets.figures(RECORDS), {})
    lines = targets.format_table(rows)
    assert len(lines) == len(rows) + 1
    assert any("distorted hex8, element-based" in line and ">= 2.00e+06" in line for line in lines)


def test_steps_quick_and_large():
    full = targets.steps({1, 2, 3, 4}, rounds=2)
    quick = targets.steps({1, 2, 3, 4}, quick=True)
    large = targets.steps({3, 4}, large=True)
    assert sum(s[2] == "newton_path.py" for s in full) == 8
    assert sum(s[2] == "newton_path.py" for s in quick) == 4
    assert not any(s[0] == "cold_warmup" for s in quick)
    assert ["--n", "20", "40", "66"] == next(s[3] for s in large if s[0] == "penalty_solve")
    assert "1e7" in next(s[3] for s in large if s[0] == "scaling")


def test_steps_pass_a_checkout_to_the_scripts_that_take_it():
    plan = targets.steps({1, 2, 3, 4}, rounds=1, package="/tmp/other")
    plain = targets.steps({1, 2, 3, 4}, rounds=1)
    assert [s[0] for s in plan] == [s[0] for s in plain]
    for (name, _, script, arguments, _), (_, _, _, before, _) in zip(plan, plain):
        if script in ("throughput.py", "newton_path.py", "cold_start.py", "scaling.py"):
            assert arguments == [*before, "--package", "/tmp/other"], name
        else:
            assert arguments == before, name          # the solves of item 3 take no --package
    assert any(s[2] == "penalty_solve.py" for s in plan)


def test_record_appends_json_lines_only_when_asked(tmp_path, monkeypatch):
    from _record import ENV, read, record
    path = tmp_path / "r.jsonl"
    monkeypatch.delenv(ENV, raising=False)
    record("x", a=1)
    assert not path.exists()
    monkeypatch.setenv(ENV, str(path))
    record("x", a=1)
    record("y", b=[1, 2])
    assert read(path) == [{"kind": "x", "a": 1}, {"kind": "y", "b": [1, 2]}]
    assert json.loads(path.read_text().splitlines()[1])["kind"] == "y"


def test_each_row_names_the_command_of_the_step_that_measured_it():
    records = [dict(r, step="throughput_distorted") if r["kind"] == "throughput" and r["distort"] > 0 else
               dict(r, step=f"newton_path_{r['scene']}_{r['round']}") if r["kind"] == "newton_path" else r
               for r in RECORDS]
    commands = {"throughput_distorted": "benchmarks/throughput.py --distort 0.1",
                "newton_path_hex27_0": "benchmarks/newton_path.py --scene hex27",
                "newton_path_tet10_0": "benchmarks/newton_path.py --scene tet10"}
    rows = {r["key"]: r for r in targets.table(targets.figures(records), commands)}
    assert rows["hex8_segment"]["command"] == "benchmarks/throughput.py --distort 0.1"
    assert rows["hex27_element"]["command"] == "benchmarks/newton_path.py --scene hex27"
    assert rows["tet10_segment"]["command"] == "benchmarks/newton_path.py --scene tet10"
    assert rows["lagrange_cpu"]["command"] == ""                  # its record names no step here
