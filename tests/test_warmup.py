"""A warm-up limited to a scene's element types compiles what such a scene runs, and nothing else."""
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import mortar1d3d as m13
from mortar1d3d import cli

ROOT = Path(__file__).resolve().parent.parent

# In a fresh process (the test run's kernel cache, cold or warm: loading a kernel from the cache
# adds its signature just as compiling it does): the scoped warm-up, then the signatures of every
# kernel of the package, then a larger scene of the same kind, then the signatures again.
SCOPED_RUN = textwrap.dedent("""
    import json, sys
    import numba
    import mortar1d3d as m
    from mortar1d3d.elements.solid import registry

    def signatures():
        seen, total = set(), 0
        for name, module in list(sys.modules.items()):
            if not name.startswith("mortar1d3d"):
                continue
            for value in list(vars(module).values()):
                if isinstance(value, numba.core.dispatcher.Dispatcher) and id(value) not in seen:
                    seen.add(id(value))
                    total += len(value.signatures)
        return total

    element, integrations, scene = json.loads(sys.argv[1])
    m.warmup(elements=[element], integrations=integrations, physics=False)
    types = {t.DESCRIPTOR.name: len(t.shape.signatures) + len(t.deriv.signatures) for t in registry.SOLID_TYPES}
    before = signatures()
    beams, solid = m.generate.fibre_cube(*scene)
    if element != "hexahedron":
        solid = m.generate.box((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (scene[0],) * 3, element=element)
    for integration in integrations:
        ops = m.assemble_mortar(beams, solid, integration=integration, n_gauss=4)
    print(json.dumps(dict(types=types, before=before, after=signatures(),
                          embedded=ops.embedded_length, length=ops.beam_length)))
""")


def scoped(element, integrations, scene):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-c", SCOPED_RUN, json.dumps([element, integrations, scene])],
                          env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_demos_warmup_compiles_what_a_hex8_scene_runs_and_no_other_type():
    """The demo's warm-up (hex8, both integrations, no physics): a larger hex8 scene afterwards
    compiles or loads no further kernel, and no other element type's kernels were compiled."""
    out = scoped("hexahedron", ["segment", "element"], [4, 20, 5])
    assert out["after"] == out["before"] > 0
    assert {name: n for name, n in out["types"].items() if name != "hexahedron"} == \
        {name: 0 for name in out["types"] if name != "hexahedron"}
    assert out["embedded"] == pytest.approx(out["length"], rel=1e-12)


def test_a_tet10_warmup_compiles_tet10_and_no_third_type():
    """tet10, element-based: its kernels are compiled (called lazily by the dispatch), no type but
    tet10 and the linked hex8 has any, and a larger tet10 scene compiles nothing more."""
    out = scoped("tetra10", ["element"], [3, 4, 3])
    assert out["types"]["tetra10"] > 0
    assert {name: n for name, n in out["types"].items() if name not in ("tetra10", "hexahedron")} == \
        {name: 0 for name in out["types"] if name not in ("tetra10", "hexahedron")}
    assert out["after"] == out["before"] > 0
    assert out["embedded"] == pytest.approx(out["length"], rel=1e-12)


def test_warmup_names_an_unknown_element_type_or_integration():
    with pytest.raises(ValueError, match="unknown solid element type 'hex'.*hexahedron"):
        m13.warmup(elements=["hex"])
    with pytest.raises(ValueError, match="unknown integration 'mortar'.*segment, element, auto"):
        m13.warmup(elements=["hexahedron"], integrations=["mortar"])


def test_the_command_line_warmup_reports_a_bad_type(capsys):
    assert cli.main(["warmup", "--elements", "hex", "--no-physics"]) == 2
    assert "unknown solid element type 'hex'" in capsys.readouterr().err
