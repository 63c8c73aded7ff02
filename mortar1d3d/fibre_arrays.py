"""``[[fibres]]`` of a scene: many fibres from one table, each its own beam (docs/scene_reference.md).

A ``[[fibres]]`` entry is either random straight fibres in a box
(:func:`~mortar1d3d.generate.fibres_in_box`) or a family of helices on a cylinder
(:func:`~mortar1d3d.generate.helices_on_cylinder`). It expands into ``count`` ordinary
``[[beams]]`` entries (a ``line`` or ``helix`` curve, the entry's ``elements``, ``model`` and
``section``), appended after the scene's own ``[[beams]]`` in order: 50 fibres are 50 beams, with
their own indices for ``beam:<i>`` sets, their own coupled length and warnings.
"""
from .errors import SceneError

#: keys of a [[fibres]] entry besides those of its kind
COMMON_KEYS = ("count", "elements", "model", "section")
BOX_KEYS = ("box", "length", "orientation", "min_spacing", "seed")
HELIX_KEYS = ("cylinder",)
MAX_FIBRES = 100_000


def expand(value, i):
    """Validate ``fibres[i]`` and return its fibres as beam tables (dicts in the ``[[beams]]`` layout).

    Errors name ``fibres[i].<key>``; the beam tables are validated by the caller (as beams).
    """
    from . import generate
    from .scene import _choice, _integer, _list, _number, _points, _table, _vector

    path = f"fibres[{i}]"
    _table(value, path, COMMON_KEYS + BOX_KEYS + HELIX_KEYS, required=("count", "elements", "section"))
    count = _integer(value["count"], f"{path}.count", 1, MAX_FIBRES)
    if ("box" in value) == ("cylinder" in value):
        raise SceneError(f"{path}: give exactly one of box (random straight fibres) or cylinder (helices)")
    common = {key: value[key] for key in ("elements", "model", "section") if key in value}
    if "cylinder" in value:
        extra = [k for k in BOX_KEYS if k in value]
        if extra:
            raise SceneError(f"{path}.{extra[0]}: belongs to box fibres, not to a cylinder of helices")
        c = _table(value["cylinder"], f"{path}.cylinder", ("centre", "axis", "radius", "length", "turns", "phase"),
                   required=("centre", "axis", "radius", "length", "turns"))
        axis = _vector(c["axis"], f"{path}.cylinder.axis")
        if not axis.any():
            raise SceneError(f"{path}.cylinder.axis: must not be zero")
        helices = generate.helices_on_cylinder(
            count, _vector(c["centre"], f"{path}.cylinder.centre"), axis,
            _number(c["radius"], f"{path}.cylinder.radius", low=0.0, low_open=True),
            _number(c["length"], f"{path}.cylinder.length", low=0.0, low_open=True),
            _number(c["turns"], f"{path}.cylinder.turns"),
            _number(c.get("phase", 0.0), f"{path}.cylinder.phase"))
        return [dict(common, curve={"helix": h}) for h in helices]
    box = _points(value["box"], f"{path}.box")
    if len(box) != 2 or not (box[1] > box[0]).all():
        raise SceneError(f"{path}.box: expected two corners [[x0, y0, z0], [x1, y1, z1]] with x1 > x0 etc.")
    length = value.get("length", 0.3)
    if isinstance(length, dict):
        _table(length, f"{path}.length", ("uniform", "normal"))
        if len(length) != 1:
            raise SceneError(f"{path}.length: give one of uniform = [a, b] or normal = [mean, std]")
        kind = next(iter(length))
        p, q = (_number(v, f"{path}.length.{kind}[{k}]", low=0.0)
                for k, v in enumerate(_list(length[kind], f"{path}.length.{kind}", 2)))
        if not (p > 0.0 and (q >= p if kind == "uniform" else True)):
            raise SceneError(f"{path}.length.{kind}: expected " + ("0 < a <= b" if kind == "uniform" else "mean > 0"))
        length = {kind: [p, q]}
    else:
        length = _number(length, f"{path}.length", low=0.0, low_open=True)
    orientation = value.get("orientation", "isotropic")
    if isinstance(orientation, str):
        orientation = _choice(orientation, f"{path}.orientation", ("isotropic",))
    elif isinstance(orientation, dict):
        _table(orientation, f"{path}.orientation", ("direction", "spread"), required=("direction",))
        orientation = {"direction": _vector(orientation["direction"], f"{path}.orientation.direction"),
                       "spread": _number(orientation.get("spread", 0.0), f"{path}.orientation.spread",
                                         low=0.0, high=180.0)}
    else:
        orientation = _vector(orientation, f"{path}.orientation")
    spacing = _number(value.get("min_spacing", 0.0), f"{path}.min_spacing", low=0.0)
    seed = _integer(value.get("seed", 0), f"{path}.seed", 0)
    try:
        ends = generate.fibres_in_box(count, box[0], box[1], length=length, orientation=orientation,
                                      min_spacing=spacing, seed=seed)
    except ValueError as exc:
        raise SceneError(f"{path}: {exc}") from None
    return [dict(common, curve={"line": [list(p), list(q)]}) for p, q in ends]
