"""Every third-party package the floorscan package imports is declared in
pyproject.toml (issue 47, item 7): its imports, at the top of a module and inside
functions, read with ast, against [project] dependencies."""

from __future__ import annotations

import ast
import re
import sys
import tomllib

from conftest import REPO

#: Import names that are not their distribution's name.
DISTRIBUTION = {
    "PIL": "pillow",
    "skimage": "scikit-image",
    "sklearn": "scikit-learn",
    "yaml": "pyyaml",
}


def imported_packages(root) -> dict[str, str]:
    """Top-level names of the absolute imports under ``root``: name -> a file importing it."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                found.setdefault(name.split(".")[0], str(path.relative_to(root)))
    return found


def declared() -> set[str]:
    deps = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    return {re.split(r"[<>=!~;\[ ]", d, maxsplit=1)[0].strip().lower() for d in deps}


def test_every_imported_package_is_declared():
    third_party = {
        name: where for name, where in imported_packages(REPO / "floorscan").items()
        if name not in sys.stdlib_module_names and name != "floorscan"
    }
    missing = {DISTRIBUTION.get(n, n).lower(): where for n, where in third_party.items()
               if DISTRIBUTION.get(n, n).lower() not in declared()}
    assert not missing, f"imported but not in pyproject.toml's dependencies: {missing}"


def test_the_check_sees_imports_inside_functions(tmp_path):
    (tmp_path / "m.py").write_text("import numpy\n\ndef f():\n    from skimage import measure\n    import PIL.Image\n"
                                   "    from . import sibling\n")
    assert set(imported_packages(tmp_path)) == {"numpy", "skimage", "PIL"}
