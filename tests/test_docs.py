"""The documentation site: no file points outside the repository, every module with ``__all__``
has an API page, and (when Sphinx is installed, as ``make docs`` installs it) the site builds
without warnings, with every internal link and anchor resolving and every public name documented.
"""
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location("check_site", ROOT / "docs" / "check_site.py")
check_site = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(check_site)

#: text files of the repository that are read by people (sources, pages, scenes, the Makefile)
TEXT_SUFFIXES = {".py", ".md", ".rst", ".toml", ".cff", ".txt", ".cfg", ""}


def _repository_files():
    out = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.split()
    return [ROOT / f for f in out if (ROOT / f).suffix in TEXT_SUFFIXES and (ROOT / f).is_file()]


# a note outside the repository ("design.md", a sibling folder), or a path of one machine
OUTSIDE = re.compile(r"design\.md|\.\./shared|/work/|/home/\w+/")


def test_no_file_points_outside_the_repository():
    hits = []
    for path in _repository_files():
        if path == Path(__file__).resolve():
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            if OUTSIDE.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()[:100]}")
    assert not hits, "\n".join(hits)


def test_relative_links_of_markdown_files_resolve():
    """README, CHANGELOG and docs/*.md link only to files that exist in the repository."""
    link = re.compile(r"\]\(([^)#\s]+)(#[^)]*)?\)")
    bad = []
    for path in [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        if not path.exists() or "_build" in path.parts:
            continue
        for target, _ in link.findall(path.read_text(encoding="utf-8")):
            if re.match(r"[a-z]+:", target):
                continue
            if not (path.parent / target).exists():
                bad.append(f"{path.relative_to(ROOT)}: {target}")
    assert not bad, bad


def test_every_module_with_all_has_an_api_page():
    pages = check_site.api_pages()
    missing = [m for m in check_site.modules_with_all() if m not in pages]
    assert not missing, f"add docs/api/<name>.rst with '.. automodule::' for {missing}"
    assert "mortar1d3d" in pages and "mortar1d3d.generate" in pages


def test_the_link_checker_finds_a_broken_link_and_anchor(tmp_path):
    (tmp_path / "a.html").write_text('<p id="here"><a href="b.html#there">x</a><a href="a.html#here">y</a>'
                                     '<a href="gone.html">z</a><a href="https://example.org/">w</a></p>')
    (tmp_path / "b.html").write_text('<p id="elsewhere"></p>')
    problems = sorted((str(p), link, why) for p, link, why in check_site.broken_links(tmp_path))
    assert problems == [("a.html", "b.html#there", "no such anchor"), ("a.html", "gone.html", "no such file")]


def test_docs_build_without_warnings(tmp_path):
    if importlib.util.find_spec("sphinx") is None or importlib.util.find_spec("myst_parser") is None \
            or importlib.util.find_spec("numpydoc") is None:
        pytest.skip("Sphinx, myst-parser or numpydoc not installed (the 'docs' extra; `make docs` installs it)")
    out = tmp_path / "html"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q",
                          str(ROOT / "docs"), str(out)], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr[-4000:]
    assert check_site.broken_links(out) == []
    assert check_site.undocumented(out) == []
    for page in ("getting_started", "theory", "scene_reference", "conventions", "own_solver", "performance",
                 "validation", "tutorials/index", "api/index"):
        assert (out / f"{page}.html").exists(), page


def test_scene_reference_names_every_key_and_choice():
    """Every key that mortar1d3d/scene.py accepts, and every choice it offers, is on the page."""
    import mortar1d3d.scene as scene_module
    source = (ROOT / "mortar1d3d" / "scene.py").read_text(encoding="utf-8")
    page = (ROOT / "docs" / "scene_reference.md").read_text(encoding="utf-8")
    keys = set()
    for allowed in re.findall(r"_table\([^()]*?,\s*[^()]*?,\s*\(([^()]*)\)", source):
        keys.update(re.findall(r'"(\w+)"', allowed))
    assert {"mesh", "material", "curve", "section", "penalty", "search_points", "max_cuts", "clamp"} <= keys
    choices = set(scene_module.MATERIAL_MODELS) | set(scene_module.BEAM_MODELS) | set(scene_module.LOAD_TYPES) \
        | set(scene_module.SOLVERS) | set(scene_module.SOLID_ELEMENTS)
    for call in re.findall(r'_choice\([^\n]*\(([^()]*)\)\)', source):
        choices.update(re.findall(r'"(\w+)"', call))
    forms = ("`{}`", '`"{}"`', "`[{}]`", "`[[{}]]`")
    missing = sorted(k for k in keys | choices if not any(f.format(k) in page for f in forms))
    assert not missing, f"docs/scene_reference.md does not name {missing}"
