"""Checks of the built HTML site (``make docs`` and tests/test_docs.py); no network.

1. Internal links: every ``href``/``src`` without a scheme points to a file of the build, and
   its ``#anchor``, if any, to an ``id`` on that page.
2. API coverage: every name of ``__all__`` of each module that has an API page appears as a
   documented object (a signature name) on that page.

    python docs/check_site.py BUILD_DIR        # exit status 1 and one line per problem
"""
import html.parser
import importlib
import sys
from pathlib import Path
from urllib.parse import unquote, urlsplit

DOCS = Path(__file__).resolve().parent


class _Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.ids, self.names = [], set(), set()
        self._in_name = 0

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "a" and "name" in attrs:
            self.ids.add(attrs["name"])
        for key in ("href", "src"):
            if attrs.get(key):
                self.links.append(attrs[key])
        if tag == "span" and "descname" in (attrs.get("class") or "").split():
            self._in_name += 1

    def handle_endtag(self, tag):
        if tag == "span" and self._in_name:
            self._in_name -= 1

    def handle_data(self, data):
        if self._in_name and data.strip():
            self.names.add(data.strip())


def _parse(path):
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def broken_links(build):
    """``[(page, link, reason)]`` of the internal links of ``build`` that lead nowhere."""
    build = Path(build)
    pages = {p: _parse(p) for p in build.rglob("*.html")}
    problems = []
    for page, parsed in pages.items():
        for link in parsed.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or link.startswith("mailto:"):
                continue
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if not target.exists():
                problems.append((page.relative_to(build), link, "no such file"))
                continue
            if parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    problems.append((page.relative_to(build), link, "no such anchor"))
    return problems


def api_pages():
    """``{module name: API page (relative .html path)}`` from the automodule lines of docs/api."""
    out = {}
    for rst in sorted((DOCS / "api").glob("*.rst")):
        for line in rst.read_text(encoding="utf-8").splitlines():
            if line.startswith(".. automodule::"):
                out[line.split("::", 1)[1].strip()] = f"api/{rst.stem}.html"
    return out


def modules_with_all():
    """Dotted names of the package's modules that declare ``__all__`` (read from the sources)."""
    root = DOCS.parent / "mortar1d3d"
    out = []
    for path in sorted(root.rglob("*.py")):
        if any(line.startswith("__all__") for line in path.read_text(encoding="utf-8").splitlines()):
            parts = path.relative_to(root.parent).with_suffix("").parts
            out.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return out


def undocumented(build):
    """``[(module, name)]`` of public names missing from their module's API page."""
    build = Path(build)
    missing = []
    for module, page in api_pages().items():
        names = _parse(build / page).names
        for name in importlib.import_module(module).__all__:
            if f"{module}.{name}" in api_pages():        # a submodule: its own page
                continue
            if name.split(".")[-1] not in names:
                missing.append((module, name))
    return missing


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print(__doc__)
        return 2
    build = Path(argv[0])
    problems = [f"{page}: {link}: {why}" for page, link, why in broken_links(build)]
    problems += [f"api: {m}.{n} is not documented" for m, n in undocumented(build)]
    problems += [f"api: {m} declares __all__ but has no API page" for m in modules_with_all()
                 if m not in api_pages()]
    for p in problems:
        print(p)
    print(f"check_site: {len(problems)} problem(s) in {build}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
