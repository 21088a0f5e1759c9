"""Every third-party package the floorscan package imports is declared in
pyproject.toml (issue 47, item 7): its imports, at the top of a module and inside
functions, read with ast, against [project] dependencies."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from pathlib import Path

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


def normal(name: str) -> str:
    """A distribution's name as PEP 503 compares them: lower case, runs of ``-_.`` one ``-``."""
    return re.sub(r"[-_.]+", "-", name).lower()


def declared(pyproject=REPO / "pyproject.toml") -> set[str]:
    deps = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"]["dependencies"]
    return {normal(re.split(r"[<>=!~;\[ ]", d, maxsplit=1)[0].strip()) for d in deps}


def undeclared(root, names: set[str]) -> dict[str, str]:
    """The third-party distributions the modules under ``root`` import that ``names``
    (normalised) lacks: distribution -> a file importing it."""
    third_party = {
        name: where for name, where in imported_packages(root).items()
        if name not in sys.stdlib_module_names and name != "floorscan"
    }
    return {normal(DISTRIBUTION.get(n, n)): where for n, where in third_party.items()
            if normal(DISTRIBUTION.get(n, n)) not in names}


def test_every_imported_package_is_declared():
    missing = undeclared(REPO / "floorscan", declared())
    assert not missing, f"imported but not in pyproject.toml's dependencies: {missing}"


def test_the_check_finds_a_planted_undeclared_import(tmp_path):
    """The check above cannot pass vacuously: a package imported inside a function that
    pyproject.toml lacks is found (by its distribution's name), the declared ones, the
    standard library and the package itself are not."""
    package = tmp_path / "floorscan" / "walls"
    package.mkdir(parents=True)
    (package / "fit.py").write_text("import os\nimport numpy as np\nfrom floorscan.core import grid\n\n"
                                    "def f():\n    import requests\n    from skimage import measure\n")
    assert undeclared(tmp_path / "floorscan", declared()) == {"requests": "walls/fit.py"}
    assert undeclared(tmp_path / "floorscan", declared() - {"scikit-image"}) == {
        "requests": "walls/fit.py", "scikit-image": "walls/fit.py"}


def test_the_check_sees_imports_inside_functions(tmp_path):
    (tmp_path / "m.py").write_text("import numpy\n\ndef f():\n    from skimage import measure\n    import PIL.Image\n"
                                   "    from . import sibling\n")
    assert set(imported_packages(tmp_path)) == {"numpy", "skimage", "PIL"}
