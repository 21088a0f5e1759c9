"""The layout of ../shared/ARCHITECTURE.md, checked on the source (issue 25).

- Modules are small: none over :data:`MAX_LINES` lines.
- Imports point down only: a stage package imports ``floorscan.core`` and the packages
  of earlier stages (:data:`LAYER`), never a later one; ``core`` imports no stage.
- No import cycle between modules, counting imports inside functions.
- Names used across modules are public: no module of the package or script imports
  another module's ``_private`` name (issue 37).
"""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "floorscan"
MAX_LINES = 500

#: Layer of each subpackage: a module may import its own package and lower layers.
#: The simulator stands beside ingest (both make the input of the pipeline).
LAYER = {
    "core": 0,
    "ingest": 1,
    "sim": 1,
    "register": 2,
    "select": 3,
    "walls": 4,
    "floorplan": 5,
    "score": 6,
    "figures": 7,
}


def modules() -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
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


def graph() -> dict[str, set[str]]:
    mods = modules()
    known = set(mods)
    return {name: imports(name, path, known) for name, path in mods.items()}


def layer(module: str) -> tuple[str, int | None]:
    parts = module.split(".")
    sub = parts[1] if len(parts) > 1 else ""
    return sub, LAYER.get(sub)


def test_every_subpackage_has_a_layer():
    subs = {p.name for p in PACKAGE.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert subs == set(LAYER), f"subpackages without a layer: {sorted(subs - set(LAYER))}"
    # the `floorscan` command (ARCHITECTURE: floorscan/cli.py runs Snakemake, no stage logic)
    stray = sorted(p.name for p in PACKAGE.glob("*.py") if p.name not in ("__init__.py", "cli.py"))
    assert stray == [], f"modules outside the stage packages and core: {stray}"


def test_no_module_is_over_the_limit():
    """Every module at once: a failure names each module over the limit."""
    sizes = {name: len(path.read_text().splitlines()) for name, path in modules().items()}
    over = [f"{name}: {n} lines" for name, n in sorted(sizes.items()) if n > MAX_LINES]
    assert not over, f"over {MAX_LINES} lines (split them by operation): " + "; ".join(over)


def test_imports_point_down_only():
    wrong = []
    for name, targets in graph().items():
        sub, rank = layer(name)
        for t in sorted(targets):
            tsub, trank = layer(t)
            if tsub == sub or rank is None or trank is None:
                continue
            if trank >= rank:
                wrong.append(f"{name} -> {t}")
    assert wrong == [], "imports of a later (or a sibling) stage:\n" + "\n".join(wrong)


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
