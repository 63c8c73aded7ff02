"""Scenes: what is simulated, from Python or a TOML file (docs/scene_reference.md).

A :class:`Scene` holds validated, normalised plain data (numbers, strings, lists, and in Python
also mesh objects or callables). It says what exists and what happens; :mod:`mortar1d3d.model`
turns it into operators, and :func:`plan` lists the effects :func:`solve` will run.

Every error names the key path, e.g. ``beams[1].section.radius: expected a number > 0, got -2``.
"""
import math
import tomllib
from pathlib import Path

import numpy as np

from .elements.solid.dispatch import NODAL_ELEMENTS as SOLID_ELEMENTS
from .errors import SceneError  # noqa: F401 (raised here; mortar1d3d.scene.SceneError stays importable)
from .generate import FACE_SETS as BOX_FACES  # noqa: F401 (the face set names of a generated box)
from .mesh import BeamMesh, SolidMesh
from .physics.beam_types import BEAM_TYPES, DEFAULT_BEAM_TYPE, PLANNED_BEAM_TYPES

MATERIAL_MODELS = ("linear_elastic", "saint_venant_kirchhoff", "neo_hooke")
#: beam models a scene may name (the registry's, then the planned ones) and those that run
IMPLEMENTED_BEAM_MODELS = tuple(BEAM_TYPES)
BEAM_MODELS = IMPLEMENTED_BEAM_MODELS + PLANNED_BEAM_TYPES
LOAD_TYPES = ("point", "traction", "pressure", "body", "moment", "line", "line_moment")
SOLVERS = ("auto", "direct", "amg", "block")
# "petsc": distributed assembly and solve under MPI (mortar1d3d.distributed, the optional extra "mpi")
BACKENDS = ("serial", "petsc")


#: every number of a scene is 0 or has a magnitude in [MIN_MAGNITUDE, MAX_MAGNITUDE]: physical data in
#: any consistent unit system is far inside (penalties ~1e24, coordinates 1e-6..1e6), and products
#: of a few such numbers (E r⁴, ε κ, h³ det J) stay inside the float range, so nothing overflows
#: to inf or underflows to 0 downstream
MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-30, 1e30


#: generated meshes stay allocatable: a fuzzed ``cells = [1e6, 1e6, 1e6]`` must not exhaust memory
MAX_BOX_CELLS = 2_000_000
MAX_BEAM_ELEMENTS = 1_000_000


_MISSING = object()


def _fail(path, message):
    raise SceneError(f"{path}: {message}")


def _describe(value):
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def _table(value, path, allowed, required=()):
    if not isinstance(value, dict):
        _fail(path, f"expected a table (dict), got {_describe(value)}")
    unknown = [k for k in value if k not in allowed]
    if unknown:
        _fail(f"{path}.{unknown[0]}" if path else unknown[0],
              f"unknown key; allowed keys here: {', '.join(allowed)}")
    for key in required:
        if key not in value:
            _fail(f"{path}.{key}" if path else key, "missing (required)")
    return value


def _number(value, path, *, low=None, high=None, low_open=False, high_open=False):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        _fail(path, f"expected a number, got {_describe(value)}")
    try:
        value = float(value)
    except OverflowError:       # a TOML integer beyond the float range
        _fail(path, f"expected a number of magnitude <= {MAX_MAGNITUDE:g}, got an integer with "
                    f"{len(str(abs(value)))} digits")
    if not math.isfinite(value):
        _fail(path, f"expected a finite number, got {value}")
    if value != 0.0 and not MIN_MAGNITUDE <= abs(value) <= MAX_MAGNITUDE:
        _fail(path, f"expected 0 or a magnitude in [{MIN_MAGNITUDE:g}, {MAX_MAGNITUDE:g}], got {value:g} "
                    "(products of such numbers overflow or underflow; check the units)")
    if low is not None and (value <= low if low_open else value < low):
        _fail(path, f"expected a number {'>' if low_open else '>='} {low:g}, got {value:g}")
    if high is not None and (value >= high if high_open else value > high):
        _fail(path, f"expected a number {'<' if high_open else '<='} {high:g}, got {value:g}")
    return value


def _integer(value, path, low=1, high=None):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        _fail(path, f"expected an integer, got {_describe(value)}")
    value = int(value)
    if value < low or (high is not None and value > high):
        _fail(path, f"expected an integer in [{low}, {high if high is not None else '∞'}], got {value}")
    return value


def _choice(value, path, choices):
    if not isinstance(value, str):
        _fail(path, f"expected one of {', '.join(map(repr, choices))}, got {_describe(value)}")
    if value not in choices:
        _fail(path, f"unknown value {value!r}; expected one of {', '.join(map(repr, choices))}")
    return value


def _vector(value, path, n=3):
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        _fail(path, f"expected a list of {n} numbers, got {_describe(value)}")
    if len(value) != n:
        _fail(path, f"expected a list of {n} numbers, got {len(value)} entries")
    return np.array([_number(v, f"{path}[{i}]") for i, v in enumerate(value)])


def _points(value, path, min_count=2):
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        _fail(path, f"expected a list of points [[x, y, z], ...], got {_describe(value)}")
    if len(value) < min_count:
        _fail(path, f"expected at least {min_count} points, got {len(value)}")
    return np.array([_vector(p, f"{path}[{i}]") for i, p in enumerate(value)])


def _boolean(value, path):
    if not isinstance(value, (bool, np.bool_)):
        _fail(path, f"expected true or false, got {_describe(value)}")
    return bool(value)


# --------------------------------------------------------------------------------------------
# sections
# --------------------------------------------------------------------------------------------
def _solid(value, base_dir):
    path = "solid"
    _table(value, path, ("mesh", "material"), required=("mesh",))
    if "material" not in value:
        _fail("solid.material", "missing: give e.g. { model = \"saint_venant_kirchhoff\", E = 1e9, nu = 0.3 }")
    mesh = value["mesh"]
    if isinstance(mesh, SolidMesh):
        mesh_spec = mesh
    elif isinstance(mesh, (str, Path)):
        file = Path(mesh)
        if not file.is_absolute():
            file = Path(base_dir or ".") / file
        if not file.exists():
            _fail("solid.mesh", f"mesh file {str(file)!r} does not exist")
        mesh_spec = file
    elif isinstance(mesh, dict) and any(k in mesh for k in ("pipe", "brick", "patches")):
        from .nurbs.scene import NURBS_MESHES       # an exact NURBS pipe (section), a NURBS brick, or several patches
        kind = next(k for k in ("pipe", "brick", "patches") if k in mesh)
        _table(mesh, "solid.mesh", (kind,))
        mesh_spec = {kind: NURBS_MESHES[kind][0](mesh[kind], f"solid.mesh.{kind}")}
    else:
        _table(mesh, "solid.mesh", ("box", "cells", "element", "pipe", "brick", "patches"), required=("box", "cells"))
        box = _points(mesh["box"], "solid.mesh.box")
        if len(box) != 2:
            _fail("solid.mesh.box", f"expected two corners [[x0, y0, z0], [x1, y1, z1]], got {len(box)} points")
        if not (box[1] > box[0]).all():
            _fail("solid.mesh.box", "the upper corner must be greater than the lower one in x, y and z")
        cells = [_integer(c, f"solid.mesh.cells[{i}]", 1, MAX_BOX_CELLS)
                 for i, c in enumerate(_list(mesh["cells"], "solid.mesh.cells", 3))]
        if math.prod(cells) > MAX_BOX_CELLS:
            _fail("solid.mesh.cells", f"{cells} gives {math.prod(cells)} cells; at most {MAX_BOX_CELLS} are generated")
        element = _choice(mesh.get("element", "hexahedron"), "solid.mesh.element", tuple(SOLID_ELEMENTS))
        mesh_spec = {"box": box, "cells": cells, "element": element}
    raw = _table(value["material"], "solid.material", ("model", "E", "nu", "fibres"), required=("model", "E", "nu"))
    material = {"model": _choice(raw["model"], "solid.material.model", MATERIAL_MODELS),
                "E": _number(raw["E"], "solid.material.E", low=0.0, low_open=True),
                "nu": _number(raw["nu"], "solid.material.nu", low=-1.0, high=0.5, low_open=True,
                              high_open=True)}
    if "fibres" in raw:
        material["fibres"] = [_fibre(f, f"solid.material.fibres[{i}]")
                              for i, f in enumerate(_list(raw["fibres"], "solid.material.fibres"))]
    return {"mesh": mesh_spec, "material": material}


def _fibre(value, path):
    """A fibre family of a fibre-reinforced material: direction, E, volume_fraction, optional region."""
    _table(value, path, ("direction", "E", "volume_fraction", "inside"), required=("direction", "E", "volume_fraction"))
    direction = _vector(value["direction"], f"{path}.direction")
    if np.linalg.norm(direction) == 0.0:
        _fail(f"{path}.direction", "must not be zero")
    out = {"direction": direction / np.linalg.norm(direction),
           "E": _number(value["E"], f"{path}.E", low=0.0, low_open=True),
           "volume_fraction": _number(value["volume_fraction"], f"{path}.volume_fraction", low=0.0, high=1.0,
                                      low_open=True),
           "inside": None}
    if "inside" in value:
        out["inside"] = _set_spec({"inside": value["inside"]}, path)["inside"]
    return out


def _list(value, path, n=None):
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__"):
        _fail(path, f"expected a list, got {_describe(value)}")
    if n is not None and len(value) != n:
        _fail(path, f"expected {n} entries, got {len(value)}")
    return list(value)


def _curve(value, path):
    _table(value, path, ("line", "polyline", "helix", "function", "derivative", "t"))
    kinds = [k for k in ("line", "polyline", "helix", "function") if k in value]
    if len(kinds) != 1:
        _fail(path, "give exactly one of line, polyline, helix, function")
    kind = kinds[0]
    if kind == "line":
        points = _points(value["line"], f"{path}.line")
        if len(points) != 2:
            _fail(f"{path}.line", f"expected two points, got {len(points)} (use polyline for more)")
        if np.linalg.norm(points[1] - points[0]) == 0.0:
            _fail(f"{path}.line", "the two points coincide")
        return {"line": points}
    if kind == "polyline":
        points = _points(value["polyline"], f"{path}.polyline")
        if (np.linalg.norm(np.diff(points, axis=0), axis=1) == 0.0).any():
            _fail(f"{path}.polyline", "consecutive points coincide")
        return {"polyline": points}
    if kind == "helix":
        h = _table(value["helix"], f"{path}.helix", ("centre", "axis", "radius", "length", "turns", "phase"),
                   required=("centre", "axis", "radius", "length", "turns"))
        axis = _vector(h["axis"], f"{path}.helix.axis")
        if np.linalg.norm(axis) == 0.0:
            _fail(f"{path}.helix.axis", "must not be zero")
        return {"helix": {"centre": _vector(h["centre"], f"{path}.helix.centre"), "axis": axis / np.linalg.norm(axis),
                          "radius": _number(h["radius"], f"{path}.helix.radius", low=0.0, low_open=True),
                          "length": _number(h["length"], f"{path}.helix.length", low=0.0, low_open=True),
                          "turns": _number(h["turns"], f"{path}.helix.turns"),      # < 0: left-handed
                          "phase": _number(h.get("phase", 0.0), f"{path}.helix.phase")}}
    f, df = value["function"], value.get("derivative", _MISSING)
    if not callable(f):
        _fail(f"{path}.function", "expected a callable f(t) -> (3,) (Python scenes only)")
    if df is _MISSING or not callable(df):
        _fail(f"{path}.derivative", "expected a callable df(t) -> (3,) next to function")
    t = _vector(value.get("t", [0.0, 1.0]), f"{path}.t", 2)
    return {"function": f, "derivative": df, "t": t}


def _beam(value, i, base_dir):
    path = f"beams[{i}]"
    _table(value, path, ("curve", "mesh", "elements", "model", "section", "normal", "triads", "force_rule",
                         "virtual_spins"), required=("section",))
    model = _choice(value.get("model", DEFAULT_BEAM_TYPE), f"{path}.model", BEAM_MODELS)
    if model not in IMPLEMENTED_BEAM_MODELS:
        _fail(f"{path}.model", f"{model!r} beams are not implemented yet; use one of "
                               f"{', '.join(map(repr, IMPLEMENTED_BEAM_MODELS))}")
    kind = BEAM_TYPES[model]
    if ("curve" in value) == ("mesh" in value):
        _fail(path, "give exactly one of curve or mesh")
    out = {"model": model, "normal": None}
    if "normal" in value:
        if kind.triads is None:
            _fail(f"{path}.normal", f"a {model} beam has no material frame (no triads); the reference normal "
                                    "is for beams with rotations (model = \"simo_reissner\")")
        normal = _vector(value["normal"], f"{path}.normal")
        if np.linalg.norm(normal) == 0.0:
            _fail(f"{path}.normal", "must not be zero")
        out["normal"] = normal / np.linalg.norm(normal)
    # options of the simo_reissner element (None: its default)
    from .physics.simo_reissner import FORCE_RULES, VIRTUAL_SPINS
    for key, lacks, choices in (("force_rule", "no force (shear) term of its own rule", FORCE_RULES),
                                ("virtual_spins", "no spins", VIRTUAL_SPINS)):
        out[key] = None
        if key in value:
            if kind.triads is None:
                _fail(f"{path}.{key}", f"a {model} beam has {lacks}; {key} is for model = \"simo_reissner\"")
            out[key] = _choice(value[key], f"{path}.{key}", choices)
    out["triads"] = None
    if "triads" in value:
        if kind.triads is None or "normal" in value:
            _fail(f"{path}.triads", "given reference triads are for beams with rotations (model = \"simo_reissner\"), "
                                    "instead of normal" if kind.triads is None else "give normal or triads, not both")
        triads = value["triads"]
        if isinstance(triads, (str, bytes, dict)) or not hasattr(triads, "__len__") or not len(triads):
            _fail(f"{path}.triads", "expected a list of 3×3 triads (columns g1, g2, g3), one per rotation node")
        out["triads"] = np.array([[_vector(row, f"{path}.triads[{k}][{r}]") for r, row in
                                   enumerate(_list(t, f"{path}.triads[{k}]", 3))] for k, t in enumerate(triads)])
    if "curve" in value:
        out["curve"] = _curve(value["curve"], f"{path}.curve")
        if "polyline" in out["curve"]:
            if "elements" in value:
                _fail(f"{path}.elements", "a polyline has one element per segment; leave elements out")
            out["elements"] = len(out["curve"]["polyline"]) - 1
        else:
            if "elements" not in value:
                _fail(f"{path}.elements", "missing (number of beam elements along the curve)")
            out["elements"] = _integer(value["elements"], f"{path}.elements", 1, MAX_BEAM_ELEMENTS)
    else:
        mesh = value["mesh"]
        if "elements" in value:
            _fail(f"{path}.elements", "the mesh defines the elements; leave elements out")
        if isinstance(mesh, BeamMesh):
            wanted = kind.element.name
            if mesh.element_type.name != wanted:
                _fail(f"{path}.mesh", f"{model} beams need a {wanted!r} BeamMesh, got {mesh.element_type.name!r}")
            out["mesh"] = mesh
        elif isinstance(mesh, (str, Path)):
            file = Path(mesh) if Path(mesh).is_absolute() else Path(base_dir or ".") / mesh
            if not file.exists():
                _fail(f"{path}.mesh", f"mesh file {str(file)!r} does not exist")
            out["mesh"] = file
        else:
            _fail(f"{path}.mesh", f"expected a BeamMesh or a file name, got {_describe(mesh)}")
    if kind.section_law == "shear_torsion":
        out["section"] = _shear_torsion_section(value["section"], f"{path}.section")
        return out
    s = _table(value["section"], f"{path}.section", ("E", "radius", "EA", "EI"))
    by_radius, explicit = ("E" in s or "radius" in s), ("EA" in s or "EI" in s)
    if by_radius == explicit:
        _fail(f"{path}.section", "give either E and radius (circular section) or EA and EI, not both")
    if by_radius:
        E = _number(_required(s, "E", f"{path}.section"), f"{path}.section.E", low=0.0, low_open=True)
        r = _number(_required(s, "radius", f"{path}.section"), f"{path}.section.radius", low=0.0,
                    low_open=True)
        # a beam without bending stiffness (truss): EI derived from the radius would only be ignored
        EI = E * math.pi * r ** 4 / 4.0 if kind.bending else 0.0
        out["section"] = {"EA": E * math.pi * r * r, "EI": EI, "E": E, "radius": r}
    else:
        EA = _number(_required(s, "EA", f"{path}.section"), f"{path}.section.EA", low=0.0, low_open=True)
        if kind.bending:
            EI = _number(_required(s, "EI", f"{path}.section"), f"{path}.section.EI", low=0.0, low_open=True)
        else:
            EI = _number(s.get("EI", 0.0), f"{path}.section.EI", low=0.0)
        out["section"] = {"EA": EA, "EI": EI}
    return out


def _shear_torsion_section(value, path):
    """Section of a beam with shear and torsion (``simo_reissner``), normalised to the six
    stiffnesses ``EA, GA2, GA3, GI_T, EI2, EI3`` (plus ``EI`` = the mean bending stiffness).

    Accepted forms: stiffnesses ``{EA, GA2, GA3, GI_T, EI2, EI3}``; a solid circular section
    ``{E, G | nu, radius}`` (A = πr², I2 = I3 = πr⁴/4, I_T = πr⁴/2, shear correction
    6(1 + ν)/(7 + 6ν)); or a general one ``{E, G | nu, A, I2, I3, I_T[, shear_correction]}``
    (shear correction default 1: shear areas equal to A).
    """
    keys = ("E", "G", "nu", "A", "I2", "I3", "I_T", "shear_correction", "radius",
            "EA", "GA2", "GA3", "GI_T", "EI2", "EI3")
    _table(value, path, keys)
    stiffness = ("EA", "GA2", "GA3", "GI_T", "EI2", "EI3")
    given = [k for k in stiffness if k in value]
    if given:
        other = [k for k in value if k not in stiffness]
        if other:
            _fail(f"{path}.{other[0]}", "give either the stiffnesses EA, GA2, GA3, GI_T, EI2, EI3 or the material "
                                        "and geometry (E, G or nu, and radius or A, I2, I3, I_T), not both")
        out = {k: _number(_required(value, k, path), f"{path}.{k}", low=0.0, low_open=True) for k in stiffness}
    else:
        E = _number(_required(value, "E", path), f"{path}.E", low=0.0, low_open=True)
        if ("G" in value) == ("nu" in value):
            _fail(f"{path}.G", "give exactly one of G (shear modulus) and nu (Poisson's ratio)")
        if "G" in value:
            G = _number(value["G"], f"{path}.G", low=0.0, low_open=True)
            nu = E / (2.0 * G) - 1.0
        else:
            nu = _number(value["nu"], f"{path}.nu", low=-1.0, high=0.5, low_open=True, high_open=True)
            G = E / (2.0 * (1.0 + nu))
        if "radius" in value:
            for k in ("A", "I2", "I3", "I_T", "shear_correction"):
                if k in value:
                    _fail(f"{path}.{k}", "a circular section (radius) defines A, I2, I3, I_T and its shear "
                                         "correction; leave it out or give A, I2, I3, I_T instead of radius")
            r = _number(value["radius"], f"{path}.radius", low=0.0, low_open=True)
            from .physics.simo_reissner import cowper_shear_correction
            A, I2, I_T = math.pi * r * r, math.pi * r ** 4 / 4.0, math.pi * r ** 4 / 2.0
            if not -1.0 < nu < 0.5:
                # Cowper's correction needs the Poisson's ratio of an isotropic material
                _fail(f"{path}.G", f"E/(2G) - 1 = {nu:.6g} is not a Poisson's ratio in (-1, 0.5), which the circular "
                                   "section's shear correction needs; give A, I2, I3, I_T and shear_correction "
                                   "instead of radius")
            I3, k = I2, cowper_shear_correction(nu)
        else:
            A, I2, I3, I_T = (_number(_required(value, key, path), f"{path}.{key}", low=0.0, low_open=True)
                              for key in ("A", "I2", "I3", "I_T"))
            k = _number(value.get("shear_correction", 1.0), f"{path}.shear_correction", low=0.0, low_open=True)
        out = {"EA": E * A, "GA2": G * k * A, "GA3": G * k * A, "GI_T": G * I_T, "EI2": E * I2, "EI3": E * I3}
    out["EI"] = 0.5 * (out["EI2"] + out["EI3"])
    return out


def _required(table, key, path):
    if key not in table:
        _fail(f"{path}.{key}", "missing (required)")
    return table[key]


def _coupling(value):
    path = "coupling"
    _table(value, path, ("constraint", "integration", "enforcement", "penalty", "lm", "n_gauss", "search_points",
                         "negative_kappa", "rotational"))
    out = {"constraint": _choice(value.get("constraint", "mortar"), "coupling.constraint", ("mortar", "gauss_point")),
           "integration": _choice(value.get("integration", "segment"), "coupling.integration",
                                  ("segment", "element", "auto", "element_boundary")),
           "enforcement": _choice(value.get("enforcement", "penalty"), "coupling.enforcement", ("penalty", "lagrange")),
           "lm": _choice(value.get("lm", "line2"), "coupling.lm", ("line2", "line3", "line4")),
           "n_gauss": _integer(value.get("n_gauss", 6), "coupling.n_gauss", 1, 64),
           "search_points": _integer(value.get("search_points", 6), "coupling.search_points", 2, 64),
           "negative_kappa": _choice(value.get("negative_kappa", "drop"), "coupling.negative_kappa", ("drop", "keep")),
           "penalty": None}
    if "penalty" in value:
        out["penalty"] = _number(value["penalty"], "coupling.penalty", low=0.0, low_open=True)
    if out["negative_kappa"] == "keep" and not (out["enforcement"] == "penalty" and out["constraint"] == "mortar"):
        _fail("coupling.negative_kappa", "'keep' is for the mortar constraint with penalty enforcement only")
    if out["constraint"] == "gauss_point" and out["enforcement"] != "penalty":
        _fail("coupling.enforcement", "the gauss_point constraint is enforced by penalty only")
    out["rotational"] = _rotational(value["rotational"]) if "rotational" in value else None
    return out


def _rotational(value):
    """``coupling.rotational``: cross-sections of beams with rotations tied to a solid triad."""
    path = "coupling.rotational"
    _table(value, path, ("triad", "enforcement", "penalty", "lm", "constraint", "forces"))
    from .physics.rotational_coupling_kernel import TRIADS
    out = {"triad": _choice(value.get("triad", "polar"), f"{path}.triad", tuple(TRIADS)),
           "enforcement": _choice(value.get("enforcement", "penalty"), f"{path}.enforcement", ("penalty", "lagrange")),
           "lm": _choice(value.get("lm", "line3"), f"{path}.lm", ("line2", "line3")),
           "constraint": _choice(value.get("constraint", "mortar"), f"{path}.constraint", ("mortar", "gauss_point")),
           "forces": _choice(value.get("forces", "variational"), f"{path}.forces", ("variational", "fourc")),
           "penalty": None}
    if "penalty" in value:
        out["penalty"] = _number(value["penalty"], f"{path}.penalty", low=0.0, low_open=True)
    if out["constraint"] == "gauss_point" and out["enforcement"] != "penalty":
        _fail(f"{path}.enforcement", "the gauss_point constraint is enforced by penalty only")
    if out["forces"] == "fourc" and not (out["constraint"] == "mortar" and out["enforcement"] == "penalty"):
        # 4C's force form is that of its mortar penalty pair; with multipliers the saddle point would
        # need the form's own constraint gradient, which is not built
        _fail(f"{path}.forces", "'fourc' is 4C's force form of the mortar constraint with penalty enforcement; "
                                "use forces = \"variational\" with constraint = \"gauss_point\" or "
                                "enforcement = \"lagrange\"")
    return out


def _set_spec(value, path):
    if isinstance(value, str):
        parts = value.split(":")
        if parts[0] == "solid" and len(parts) == 2 and parts[1]:
            return value
        if parts[0] == "beam" and len(parts) in (2, 3):
            # only plain decimal digits: int() would also take "-1" (counting from the end),
            # " 1" and "1_0"; the set must name one beam of the scene, counted from 0
            if not (parts[1].isascii() and parts[1].isdigit()):
                _fail(path, f"{value!r}: expected beam:<index>[:start|end] with <index> = 0, 1, ... (the "
                            f"position of the beam in [[beams]]), got index {parts[1]!r}")
            if len(parts) == 3 and parts[2] not in ("start", "end"):
                _fail(path, f"{value!r}: expected beam:<index>:start or beam:<index>:end")
            return value
        _fail(path, f"{value!r}: expected 'solid:x_min' … 'solid:z_max', 'solid:<point set>', "
                    "'beam:<i>', 'beam:<i>:start|end', or {{ inside = [[x0, y0, z0], [x1, y1, z1]] }}")
    _table(value, path, ("inside",), required=("inside",))
    box = _points(value["inside"], f"{path}.inside")
    if len(box) != 2 or not (box[1] >= box[0]).all():
        _fail(f"{path}.inside", "expected two corners [[x0, y0, z0], [x1, y1, z1]] with x1 >= x0 etc.")
    return {"inside": box}


def _dirichlet(value, i):
    path = f"dirichlet[{i}]"
    _table(value, path, ("on", "value", "components", "clamp", "rotation", "twist"), required=("on",))
    # an entry that prescribes a rotation (or holds the twist) fixes positions only when it says so
    # (value or components)
    rotation_only = ("rotation" in value or "twist" in value) and "value" not in value and "components" not in value
    comps = value.get("components", [] if rotation_only else ["x", "y", "z"])
    comps = _list(comps, f"{path}.components")
    if not comps and not rotation_only:
        _fail(f"{path}.components", "empty: name at least one of 'x', 'y', 'z'")
    idx = sorted({"xyz".index(_choice(c, f"{path}.components[{k}]", ("x", "y", "z"))) for k, c in enumerate(comps)})
    out = {"on": _set_spec(value["on"], f"{path}.on"),
           "value": _vector(value.get("value", [0.0, 0.0, 0.0]), f"{path}.value"),
           "components": idx, "clamp": _boolean(value.get("clamp", False), f"{path}.clamp"), "rotation": None}
    if out["clamp"] and not (isinstance(out["on"], str) and out["on"].startswith("beam:")):
        _fail(f"{path}.clamp", "clamp (fix the tangent too) applies to beam sets only")
    if "rotation" in value:
        rotation = value["rotation"]
        if not (isinstance(out["on"], str) and out["on"].startswith("beam:")):
            _fail(f"{path}.rotation", "a rotation is prescribed on beam sets only (beam:<i>, beam:<i>:start|end)")
        if isinstance(rotation, (list, tuple)) and len(rotation) != 3:
            _fail(f"{path}.rotation", f"expected the total rotation vector [θx, θy, θz] (all three components: a "
                                      f"rotation is one object, its components are not independent), got "
                                      f"{len(rotation)} entries")
        out["rotation"] = _vector(rotation, f"{path}.rotation")
    out["twist"] = _boolean(value.get("twist", False), f"{path}.twist")
    if out["twist"]:
        if not (isinstance(out["on"], str) and out["on"].startswith("beam:")):
            _fail(f"{path}.twist", "the twist is held on beam sets only (beam:<i>, beam:<i>:start|end)")
        if "rotation" in value or out["clamp"]:
            _fail(f"{path}.twist", "give twist or a whole rotation (rotation, clamp), not both: those fix the twist "
                                   "already")
    return out


def _load(value, i):
    path = f"load[{i}]"
    _table(value, path, ("type", "on", "value"), required=("type", "value"))
    kind = _choice(value["type"], f"{path}.type", LOAD_TYPES)
    out = {"type": kind}
    if kind == "body":
        if "on" in value:
            _fail(f"{path}.on", "a body force acts on the whole solid; leave 'on' out")
        out["on"] = None
    else:
        if "on" not in value:
            _fail(f"{path}.on", "missing (the set the load acts on)")
        out["on"] = _set_spec(value["on"], f"{path}.on")
    if kind == "pressure":
        out["value"] = _number(value["value"], f"{path}.value")
    else:
        out["value"] = _vector(value["value"], f"{path}.value")
    if kind in ("traction", "pressure") and not (isinstance(out["on"], str) and out["on"].startswith("solid:")):
        _fail(f"{path}.on", f"a {kind} acts on a solid surface: use 'solid:x_max' or a solid point set")
    if kind in ("line", "line_moment") and not (isinstance(out["on"], str) and out["on"].startswith("beam:")
                                               and out["on"].count(":") == 1):
        _fail(f"{path}.on", f"a {'line load' if kind == 'line' else 'line moment'} acts along a whole beam: use "
                            "'beam:<i>'")
    if kind == "moment" and not (isinstance(out["on"], str) and out["on"].startswith("beam:")):
        _fail(f"{path}.on", "a moment acts on beam nodes: use 'beam:<i>:start' or 'beam:<i>:end' (or 'beam:<i>' "
                            "for a beam with rotations)")
    return out


def _analysis(value):
    path = "analysis"
    _table(value, path, ("kinematics", "steps", "solver", "max_iterations", "rtol", "max_cuts", "backend"))
    return {"kinematics": _choice(value.get("kinematics", "nonlinear"), "analysis.kinematics", ("nonlinear", "linear")),
            "steps": _integer(value.get("steps", 1), "analysis.steps", 1, 100000),
            "solver": _choice(value.get("solver", "auto"), "analysis.solver", SOLVERS),
            "max_iterations": _integer(value.get("max_iterations", 25), "analysis.max_iterations", 1, 1000),
            "rtol": _number(value.get("rtol", 1e-8), "analysis.rtol", low=0.0, high=1.0, low_open=True, high_open=True),
            "max_cuts": _integer(value.get("max_cuts", 6), "analysis.max_cuts", 0, 50),
            "backend": _choice(value.get("backend", "serial"), "analysis.backend", BACKENDS)}


def _fibre_arrays(value, beams, base_dir):
    """Expand ``[[fibres]]`` (mortar1d3d.fibre_arrays) into beams appended to ``beams``; returns
    ``[(first beam index, count), ...]`` per entry. A beam's errors name ``fibres[i]``."""
    from .fibre_arrays import expand
    out = []
    for i, entry in enumerate(_list(value, "fibres")):
        first = len(beams)
        for k, table in enumerate(expand(entry, i)):
            try:
                beams.append(_beam(table, first + k, base_dir))
            except SceneError as exc:
                raise SceneError(str(exc).replace(f"beams[{first + k}]", f"fibres[{i}]", 1)) from None
        out.append((first, len(beams) - first))
    return out


class Scene:
    """What is simulated: solid, beams, coupling, supports, loads and the analysis.

    Build from Python with the same fields as the TOML file (docs/scene_reference.md), or with
    :meth:`from_toml` / :meth:`from_dict`. Python scenes may also pass a :class:`SolidMesh` as
    ``solid["mesh"]``, a :class:`BeamMesh` as ``beams[i]["mesh"]`` and callables as curves.

    Parameters
    ----------
    solid : dict, optional
        ``{"mesh": ..., "material": {"model", "E", "nu"}}``; a scene may hold beams only.
    beams : list of dict
    coupling, analysis : dict, optional
    dirichlet, load : list of dict
    base_dir : path, optional
        Directory that relative mesh file names are resolved against.

    Raises
    ------
    SceneError
        With the key path of the first invalid entry.
    """

    def __init__(self, solid=None, beams=(), coupling=None, dirichlet=(), load=(), analysis=None, *,
                 fibres=(), base_dir=None, name="scene"):
        self.name = name
        self.base_dir = Path(base_dir) if base_dir is not None else None
        self.solid = _solid(solid, base_dir) if solid is not None else None
        self.beams = [_beam(b, i, base_dir) for i, b in enumerate(_list(beams, "beams"))]
        self.fibres = _fibre_arrays(fibres, self.beams, base_dir)
        if self.solid is None and not self.beams:
            _fail("scene", "nothing to simulate: give a [solid] and/or [[beams]]")
        if coupling is not None and (self.solid is None or not self.beams):
            _fail("coupling", "a coupling needs both a solid and beams")
        self.coupling = _coupling(coupling if coupling is not None else {})
        self.dirichlet = [_dirichlet(d, i) for i, d in enumerate(_list(dirichlet, "dirichlet"))]
        self.loads = [_load(item, i) for i, item in enumerate(_list(load, "load"))]
        self.analysis = _analysis(analysis if analysis is not None else {})
        for i, item in enumerate(self.loads):
            if item["type"] == "body" and self.solid is None:
                _fail(f"load[{i}]", "a body force needs a solid")
            if item["type"] == "line_moment":
                beam = int(item["on"].split(":")[1])
                if beam < len(self.beams) and BEAM_TYPES[self.beams[beam]["model"]].triads is None:
                    _fail(f"load[{i}].on", f"a line moment needs a beam with rotations (simo_reissner); beam {beam} "
                                           f"is a {self.beams[beam]['model']}")
            if item["type"] == "moment":
                beam = int(item["on"].split(":")[1])
                if beam < len(self.beams) and not BEAM_TYPES[self.beams[beam]["model"]].bending:
                    _fail(f"load[{i}].on", f"a moment needs a beam with bending stiffness; beam {beam} is a "
                                           f"{self.beams[beam]['model']}")
                if (beam < len(self.beams) and BEAM_TYPES[self.beams[beam]["model"]].triads is None
                        and item["on"].count(":") != 2):
                    _fail(f"load[{i}].on", f"a moment on a {self.beams[beam]['model']} beam acts on a beam end: use "
                                           "'beam:<i>:start' or 'beam:<i>:end'")
        if self.coupling["rotational"] is not None:
            for i, b in enumerate(self.beams):
                if BEAM_TYPES[b["model"]].triads is None:
                    _fail("coupling.rotational", f"beams[{i}] is a {b['model']} beam, which has no cross-section "
                                                 "rotations to couple; use model = \"simo_reissner\" or leave out "
                                                 "coupling.rotational")
        for i, d in enumerate(self.dirichlet):
            if d["twist"]:
                beam = int(d["on"].split(":")[1])
                if beam < len(self.beams) and BEAM_TYPES[self.beams[beam]["model"]].triads is None:
                    _fail(f"dirichlet[{i}].twist", f"beam {beam} is a {self.beams[beam]['model']} beam, which has no "
                                                   "cross-section rotations to hold; twist is for simo_reissner beams")
            if d["rotation"] is not None:
                beam = int(d["on"].split(":")[1])
                if beam < len(self.beams) and BEAM_TYPES[self.beams[beam]["model"]].triads is None:
                    _fail(f"dirichlet[{i}].rotation", f"beam {beam} is a {self.beams[beam]['model']} beam, which "
                                                      "has no rotation DOFs; prescribe rotations on a "
                                                      "simo_reissner beam (a clamp fixes a tangent's direction)")

    @property
    def coupled(self):
        """True when solid and beams both exist (the coupling is then always active)."""
        return self.solid is not None and bool(self.beams)

    @classmethod
    def from_dict(cls, data, *, base_dir=None, name="scene"):
        """Scene from a nested dict with the TOML file's layout."""
        _table(data, "", ("solid", "beams", "fibres", "coupling", "dirichlet", "load", "analysis"))
        return cls(solid=data.get("solid"), beams=data.get("beams", ()), coupling=data.get("coupling"),
                   dirichlet=data.get("dirichlet", ()), load=data.get("load", ()), analysis=data.get("analysis"),
                   fibres=data.get("fibres", ()), base_dir=base_dir, name=name)

    @classmethod
    def from_toml(cls, path):
        """Read a scene file; relative mesh paths are resolved next to it."""
        path = Path(path)
        try:
            with open(path, "rb") as f:
                data = tomllib.load(f)
        except FileNotFoundError:
            raise SceneError(f"scene file {str(path)!r} does not exist") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:      # TOML files are UTF-8 text
            raise SceneError(f"{path}: not valid TOML: {exc}") from None
        except OSError as exc:      # a directory, no permission, ...
            raise SceneError(f"scene file {str(path)!r} cannot be read: {exc.strerror or exc}") from None
        return cls.from_dict(data, base_dir=path.parent, name=path.stem)

    @classmethod
    def from_4c(cls, path):
        """The scene of a 4C input file (``.4C.yaml``; :func:`mortar1d3d.io.fourc.scene_from_4c`).

        Raises
        ------
        mortar1d3d.io.fourc.FourCError
            (a SceneError) naming the section, key and value the library does not support.
        """
        from .io.fourc import scene_from_4c
        return scene_from_4c(path)[0]

    def __repr__(self):
        parts = []
        if self.solid is not None:
            parts.append(f"solid ({self.solid['material']['model']})")
        if self.beams:
            parts.append(f"{len(self.beams)} beam(s)")
        return f"Scene({self.name}: {', '.join(parts)}, {self.analysis['kinematics']}, {self.analysis['steps']} steps)"
