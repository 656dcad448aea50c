"""The layout rules, read from the sources (so they stay true).

- Data flows one way: no module imports a later stage (body → design → cut →
  pattern → drape → export; geometry and the basics below them; metrics,
  workflows and the CLI on top).
- No import cycles, also not between modules of one package (imports inside
  functions count: a lazy import only hides a cycle).
- ``core`` never imports ``bpy``; add-on operator modules never import one
  another (what they share lives in the add-on's data, sync and helper modules).
- No module in ``core`` over 500 lines.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: Layer of each part of ``core`` (a module may import its own layer and lower ones).
LAYERS = {
    "core.errors": 0, "core.fileio": 0, "core.jsontext": 0, "core.signals": 0, "core.progress": 0,
    "core.paths": 0,
    "core.geom": 1,
    "core.body": 2,
    "core.design": 3,
    "core.cut": 4,
    "core.pattern": 5,
    "core.drape": 6,
    "core.export": 7,
    "core.metrics": 8,
    "core.workflows": 9,
    "core.live": 9,      # the live re-solve loop (painting), on the workflows' solver
    "core.batch": 10,    # many bodies through the workflows on a Dask cluster
    "core.cli": 11,
    "core": 0,           # the package's own __init__: the version only
}
MAX_LINES = 500


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
        parts = parts[:len(parts) - (node.level - 1)]
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
    bad = [m for m, imported in GRAPH.items() if m.startswith("core")
           and any(t == "bpy" or t.startswith(("bpy.", "mathutils", "addon_utils")) for t in imported)]
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


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m.startswith("core")))
def test_core_module_size(module):
    n = len(MODULES[module].read_text(encoding="utf-8").splitlines())
    assert n <= MAX_LINES, f"{MODULES[module].relative_to(ROOT)} has {n} lines (at most {MAX_LINES})"


def test_the_layer_table_knows_every_core_module():
    unknown = [m for m in MODULES if m.startswith("core") and _layer(m) is None]
    assert not unknown, f"modules outside the layer table: {unknown}"
