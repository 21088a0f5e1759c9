"""The layout of ../shared/ARCHITECTURE.md, checked on the source (issues 25, 47).

- Modules are small: none over :data:`MAX_LINES` lines.
- No two stage packages import each other (:data:`STAGES`); what both need is in
  ``floorscan.core``, which imports no stage (:func:`layer_violations`, counting
  imports inside functions and every form: ``import floorscan.x``, ``from floorscan
  import x``, relative imports). The glue may import any stage: ``scripts/``, the
  rules, ``floorscan/cli.py`` (the command), the tests and benchmarks.
- No import cycle between modules, counting imports inside functions.
- Names used across modules are public: no module of the package or script imports
  another module's ``_private`` name (issue 37).
"""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "floorscan"
MAX_LINES = 500

#: The stage packages (ARCHITECTURE.md's table: one subpackage per stage name); none
#: imports another.
STAGES = {"ingest", "sim", "register", "select", "walls", "floorplan", "score", "figures"}
#: The shared layer: every stage may import it; it imports no stage.
CORE = "core"


def modules(package: Path = PACKAGE) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package at ``package``."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """The floorscan modules ``name`` imports anywhere in its file (top level or inside
    functions): ``from a.b import c`` counts ``a.b.c`` when that is a module, else ``a.b``."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in known:
                t = t.rpartition(".")[0]
            if t and t.startswith("floorscan") and t != name:
                found.add(t)
    return found


def graph(package: Path = PACKAGE) -> dict[str, set[str]]:
    mods = modules(package)
    known = set(mods)
    return {name: imports(name, path, known) for name, path in mods.items()}


def subpackage(module: str) -> str:
    """``floorscan.score.bitmap`` -> ``score``; ``""`` for the package's own modules
    (``floorscan.cli``)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES | {CORE} else ""


def layer_violations(package: Path = PACKAGE) -> list[str]:
    """``module -> imported module`` for every import, anywhere in a module of
    ``package`` (top level or inside a function), of one stage package's module by
    another stage package, or of a stage by ``core``.

    Parameters
    ----------
    package : Path
        The ``floorscan`` folder (a copy of its layout in the tests).

    Returns
    -------
    list of str
        Sorted.
    """
    wrong = []
    for name, targets in graph(package).items():
        sub = subpackage(name)
        if sub not in STAGES | {CORE}:
            continue  # the package's own modules (cli.py: the command, glue like the scripts)
        for t in targets:
            tsub = subpackage(t)
            if tsub in STAGES and tsub != sub:
                wrong.append(f"{name} -> {t}")
    return sorted(wrong)


def test_every_subpackage_is_a_stage_or_core():
    subs = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert subs == STAGES | {CORE}, f"subpackages that are neither a stage nor core: {sorted(subs - STAGES - {CORE})}"
    # the `floorscan` command (ARCHITECTURE: floorscan/cli.py runs Snakemake, no stage logic)
    stray = sorted(p.name for p in PACKAGE.glob("*.py") if p.name not in ("__init__.py", "cli.py"))
    assert stray == [], f"modules outside the stage packages and core: {stray}"


def test_no_module_is_over_the_limit():
    """Every module at once: a failure names each module over the limit."""
    sizes = {name: len(path.read_text().splitlines()) for name, path in modules().items()}
    over = [f"{name}: {n} lines" for name, n in sorted(sizes.items()) if n > MAX_LINES]
    assert not over, f"over {MAX_LINES} lines (split them by operation): " + "; ".join(over)


def test_no_stage_package_imports_another():
    """ARCHITECTURE.md: no two stage packages import each other; what both need moves
    down to core, which imports no stage."""
    wrong = layer_violations()
    assert wrong == [], "imports between stage packages (or of a stage by core):\n" + "\n".join(wrong)


def test_the_layer_check_finds_a_planted_import(tmp_path):
    """The check above cannot pass vacuously: in a copy of the layout, each form of
    import of one stage by another (top level, inside a function, ``import a.b``,
    ``from a import b``, relative) and of a stage by core is found, and the allowed
    ones (a stage's own modules, core, the command) are not."""
    root = tmp_path / "floorscan"
    files = {
        "__init__.py": "",
        "cli.py": "from floorscan.figures import page\n",  # the command: glue, allowed
        "core/__init__.py": "",
        "core/grid.py": "def f():\n    from floorscan.walls import lines\n",  # core -> a stage
        "walls/__init__.py": "",
        "walls/lines.py": "from floorscan.core import grid\nfrom . import extract\n",  # allowed
        "walls/extract.py": "import numpy\n",
        "score/__init__.py": "",
        "score/runs.py": "import floorscan.walls.lines as wl\nfrom floorscan.core.grid import f\n",
        "score/curves.py": "def g():\n    from floorscan.walls.extract import numpy\n",
        "figures/__init__.py": "from floorscan import score\n",
        "figures/page.py": "from ..walls import lines\n",
    }
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    assert layer_violations(root) == [
        "floorscan.core.grid -> floorscan.walls.lines",
        "floorscan.figures -> floorscan.score",
        "floorscan.figures.page -> floorscan.walls.lines",
        "floorscan.score.curves -> floorscan.walls.extract",
        "floorscan.score.runs -> floorscan.walls.lines",
    ]
    (root / "score/curves.py").write_text("def g():\n    from floorscan.core.grid import f\n")
    assert "floorscan.score.curves -> floorscan.walls.extract" not in layer_violations(root)


def test_no_import_cycle():
    g = graph()
    index, low, on_stack, stack, cycles = {}, {}, set(), [], []
    counter = [0]

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in g.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(g):
        if v not in index:
            visit(v)
    assert cycles == [], f"modules that import each other (directly or around a cycle): {cycles}"


def test_the_graph_sees_imports_inside_functions(tmp_path):
    """The checks above would pass vacuously if the parser missed lazy imports."""
    g = graph()
    # score.stage imports against_reference only inside write_run_scores
    assert "floorscan.score.against_reference" in g["floorscan.score.stage"]
    src = tmp_path / "m.py"
    src.write_text("def f():\n    from floorscan.core import io\n    import floorscan.core.grid\n")
    assert imports("floorscan.x.m", src, set(modules())) == {"floorscan.core.io", "floorscan.core.grid"}


def test_every_rule_runs_the_script_of_its_name():
    """One name per stage: rule ``x`` runs ``scripts/x.py``, and every script has its rule."""
    import re

    rules_dir = PACKAGE.parent / "workflow" / "rules"
    pairs = {}
    for smk in sorted(rules_dir.glob("*.smk")):
        text = smk.read_text()
        for m in re.finditer(r"^[ \t]*(?:rule|checkpoint) (\w+):\n(.*?)(?=^[ \t]*(?:rule|checkpoint) |\Z)", text, re.S | re.M):
            script = re.search(r'script:\s*\n\s*"\.\./\.\./scripts/(\w+)\.py"', m.group(2))
            if script:
                pairs[m.group(1)] = script.group(1)
    assert len(pairs) >= 20
    assert {rule: script for rule, script in pairs.items() if rule != script} == {}
    scripts = {p.stem for p in (PACKAGE.parent / "scripts").glob("*.py")}
    assert scripts == set(pairs.values())


def private_imports(paths) -> list[str]:
    """``file: from module import _name`` for every import of a floorscan module's
    private name (one leading underscore) in ``paths``: a name used across modules is
    public."""
    found = []
    for path in paths:
        tree = ast.parse(Path(path).read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("floorscan"):
                for alias in node.names:
                    if alias.name.startswith("_") and not alias.name.startswith("__"):
                        found.append(f"{Path(path).name}: from {node.module} import {alias.name}")
    return found


def test_no_module_imports_another_modules_private_name():
    """Issue 37: the package and its scripts import only public names of each other."""
    paths = [*modules().values(), *sorted((PACKAGE.parent / "scripts").glob("*.py"))]
    assert private_imports(paths) == []


def test_the_private_name_check_finds_a_planted_import(tmp_path):
    """The check above cannot pass vacuously: a stage module importing another stage's
    private name, at the top or inside a function, is found."""
    planted = tmp_path / "planted.py"
    planted.write_text(
        "from floorscan.walls.ransac import fit_wall, _best_line\n"
        "def f():\n    from floorscan.score.nearest import _densify_pairs as d\n"
    )
    assert private_imports([planted]) == [
        "planted.py: from floorscan.walls.ransac import _best_line",
        "planted.py: from floorscan.score.nearest import _densify_pairs",
    ]
