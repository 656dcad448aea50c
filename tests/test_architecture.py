"""The layout rules, read from the sources (so they stay true).

- Data flows one way: no module imports a later stage (body → design → cut →
  pattern → drape → export; geometry and the basics below them; metrics,
  workflows and the CLI on top).
- No import cycles, also not between modules of one package (imports inside
  functions count: a lazy import only hides a cycle).
- ``core`` never imports ``bpy``; add-on operator modules never import one
  another (what they share lives in the add-on's data, sync and helper modules).
- The layer table in docs/architecture.md is this file's ``LAYERS``.
- A module's size is decided by what belongs together, not by a line count: modules over
  ``SOFT_LINES`` get a warning (a prompt to look, never a failure).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: Layer of each part of ``core`` (a module may import its own layer and lower ones).
LAYERS = {
    "core.errors": 0,
    "core.fileio": 0,
    "core.jsontext": 0,
    "core.signals": 0,
    "core.progress": 0,
    "core.paths": 0,
    "core.choices": 0,
    "core.geom": 1,
    "core.body": 2,
    "core.design": 3,
    "core.cut": 4,
    "core.pattern": 5,
    "core.drape": 6,
    "core.export": 7,
    "core.marker": 8,  # the marker stage: nesting the export's pieces on a fabric width
    "core.metrics": 8,
    "core.workflows": 9,
    "core.live": 9,  # the live re-solve loop (painting), on the workflows' solver
    "core.batch": 10,  # many bodies through the workflows on a Dask cluster
    "core.cli": 11,
    "core": 0,  # the package's own __init__: the version only
}
#: modules longer than this are listed in a warning: worth a look, not a rule
SOFT_LINES = 800


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules(package: str) -> dict:
    return {_module_name(p): p for p in sorted((ROOT / package).rglob("*.py"))}


MODULES = {**_modules("core"), **_modules("ease_addon")}


def _resolve(module: str, is_package: bool, node) -> list:
    """Absolute module names imported by ``node`` in ``module``."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level == 0:
        base = node.module or ""
    else:
        parts = module.split(".")
        if not is_package:
            parts = parts[:-1]
        parts = parts[: len(parts) - (node.level - 1)]
        base = ".".join(parts + ([node.module] if node.module else []))
    out = []
    for a in node.names:
        sub = f"{base}.{a.name}" if base else a.name
        out.append(sub if sub in MODULES else base)
    return out


def _imports() -> dict:
    graph = {}
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        is_package = path.name == "__init__.py"
        found = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                found.update(_resolve(name, is_package, node))
        graph[name] = found
    return graph


GRAPH = _imports()


def _layer(module: str):
    best = None
    for prefix, layer in LAYERS.items():
        if (module == prefix or module.startswith(prefix + ".")) and (best is None or len(prefix) > len(best[0])):
            best = (prefix, layer)
    return best[1] if best else None


def test_core_imports_no_later_stage():
    bad = []
    for module, imported in GRAPH.items():
        if not module.startswith("core"):
            continue
        mine = _layer(module)
        for target in imported:
            theirs = _layer(target) if target.startswith("core") else None
            if theirs is not None and mine is not None and theirs > mine:
                bad.append(f"{module} imports {target}")
    assert not bad, "imports from a later stage:\n" + "\n".join(sorted(bad))


def test_core_never_imports_bpy():
    bad = [
        m
        for m, imported in GRAPH.items()
        if m.startswith("core")
        and any(t == "bpy" or t.startswith(("bpy.", "mathutils", "addon_utils")) for t in imported)
    ]
    assert not bad, f"core modules importing Blender: {bad}"


def _cycles(graph: dict) -> list:
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    # a package's __init__ re-exporting its submodules is not a cycle of logic: drop
    # edges from a package to its own submodules
    graph = {m: {t for t in imp if not t.startswith(m + ".")} for m, imp in GRAPH.items()}
    cycles = _cycles(graph)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_addon_operator_modules_do_not_import_each_other():
    ops = {m for m in GRAPH if m.startswith("ease_addon.") and m.endswith("_ops")}
    bad = [f"{m} imports {t}" for m in sorted(ops) for t in sorted(GRAPH[m]) if t in ops and t != m]
    assert not bad, "\n".join(bad)


def test_long_modules_are_named():
    """A soft size check: a long module is named in a warning, so a reader can ask whether it is one job."""
    import warnings

    long = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in MODULES.items()}
    long = {m: n for m, n in long.items() if n > SOFT_LINES}
    if long:
        warnings.warn(
            "modules over %d lines: %s" % (SOFT_LINES, ", ".join(f"{m} ({n})" for m, n in sorted(long.items())))
        )


def _documented_layers() -> dict:
    """docs/architecture.md's layer table (under "### Layering"): {module prefix: layer}."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = text.split("### Layering", 1)[1].split("\n\n|", 1)[1].split("\n\n", 1)[0]
    got = {}
    for row in table.splitlines()[2:]:
        layer, modules = [c.strip() for c in row.strip("|").split("|")]
        for name in modules.split(","):
            got[name.strip().strip("`").split(" ")[0]] = int(layer)
    return got


def test_the_documented_layer_table_is_the_tested_one():
    documented = _documented_layers()
    tested = {m: layer for m, layer in LAYERS.items() if m != "core"}
    assert documented == tested, {
        m: (documented.get(m), tested.get(m))
        for m in documented.keys() | tested.keys()
        if documented.get(m) != tested.get(m)
    }


def test_the_layer_table_knows_every_core_module():
    unknown = [m for m in MODULES if m.startswith("core") and _layer(m) is None]
    assert not unknown, f"modules outside the layer table: {unknown}"
