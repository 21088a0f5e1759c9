"""Issue 47, item 4: no HTML page is built by string concatenation in Python; the pages
are Jinja2 templates (floorscan/figures/templates, rendered by floorscan.figures.pages)."""

import ast
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: An HTML element of a page's markup (not ``<svg``, ``<script``, ``<!DOCTYPE``: an SVG's text is
#: checked for them).
_MARKUP = re.compile(r"<(?:html|head|body|style|table|thead|tbody|tr|td|th|p|div|section|nav|h[1-6]|ul|li|a|img)\b",
                     re.I)

#: Modules that still build a page in Python, each with why: the list must shrink, never grow.
NOT_YET_TEMPLATES: set[str] = set()


def _string_constants(tree: ast.AST):
    """Every string constant of a module but its docstrings (f-strings' parts included)."""
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docstrings.add(id(body[0].value))
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            yield node


def markup_in(path: Path) -> list[str]:
    """``line: snippet`` of each string constant of a module holding HTML markup."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [f"{node.lineno}: {node.value[:60]!r}" for node in _string_constants(tree) if _MARKUP.search(node.value)]


def test_no_page_is_built_in_python():
    found = {}
    for path in sorted([*(REPO / "floorscan").rglob("*.py"), *(REPO / "scripts").glob("*.py")]):
        hits = markup_in(path)
        if hits:
            found[path.relative_to(REPO).as_posix()] = hits
    assert set(found) == NOT_YET_TEMPLATES, {k: v for k, v in found.items() if k not in NOT_YET_TEMPLATES}


def test_the_check_finds_a_page_built_in_python(tmp_path):
    """The check is not blind: an f-string page and a joined list of tags are found, a
    docstring naming <table> is not."""
    module = tmp_path / "page.py"
    module.write_text('"""Writes a <table>."""\n'
                      'def page(title):\n'
                      '    """The <html> page."""\n'
                      '    return f"<h1>{title}</h1>" + "\\n".join(["<p>", "</p>"])\n')
    assert [hit.split(":")[0] for hit in markup_in(module)] == ["4", "4"]


def test_the_building_page_is_its_template_escaped():
    """The building's page (floorscan.floorplan.building.building_page): one row a floor
    with its numbers, links to its front page, plan and GeoJSON, the names escaped."""
    import pandas as pd

    from floorscan.core.plan_tables import PLAN_SCHEMAS
    from floorscan.floorplan.building import Floor, building_page
    from floorscan.floorplan.plan import FloorPlan

    empty = FloorPlan(walls=pd.DataFrame(columns=list(PLAN_SCHEMAS["walls"].names)),
                      faces=pd.DataFrame(columns=list(PLAN_SCHEMAS["faces"].names)))  # fmt: skip
    page = building_page([Floor("ground", "Ground <floor>", 0.0), Floor("first floor", "First", 3.25)],
                         {"ground": empty, "first floor": empty}, "Lab & annex")  # fmt: skip
    assert "<title>Lab &amp; annex</title>" in page and "Ground &lt;floor&gt;" in page
    assert page.count("<tr><td>") == 2 and "<td>3.25</td>" in page
    assert 'href="../first%20floor/front.html"' in page and 'href="first%20floor.geojson"' in page
    assert "2 floors in one IFC model" in page
