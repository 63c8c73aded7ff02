"""Every public name the README shows (``m13.X.Y``, ``mortar1d3d.X.Y``, ``from mortar1d3d.X import Y``)
resolves: a restructuring that moves code keeps the names users were told about (issue 17)."""
import importlib
import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
_DOTTED = re.compile(r"\b(?:m13|mortar1d3d)((?:\.[A-Za-z_]\w*)+)")
_FROM = re.compile(r"^\s*from (mortar1d3d(?:\.\w+)*) import ([\w, ]+)", re.MULTILINE)


def _names():
    text = README.read_text(encoding="utf-8")
    names = {"mortar1d3d" + m.group(1) for m in _DOTTED.finditer(text)}
    for module, imported in _FROM.findall(text):
        names.update(f"{module}.{name.strip()}" for name in imported.split(",") if name.strip())
    return sorted(names)


def _resolve(dotted):
    """The object a dotted name refers to, importing submodules on the way."""
    parts = dotted.split(".")
    obj = importlib.import_module(parts[0])
    for i, part in enumerate(parts[1:], start=1):
        if hasattr(obj, part):
            obj = getattr(obj, part)
        else:
            obj = importlib.import_module(".".join(parts[: i + 1]))
    return obj


def test_the_readme_names_something():
    names = _names()
    assert "mortar1d3d.solve" in names and "mortar1d3d.io.write_mortar" in names, names


@pytest.mark.parametrize("name", _names())
def test_readme_name_resolves(name):
    assert _resolve(name) is not None
