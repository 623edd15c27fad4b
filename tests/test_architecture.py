"""The house rules of core_se3, read from its source (docs/ARCHITECTURE.md):

* layers import only downward: every import of a core_se3 module -- at module level or inside a
  function -- goes to the same layer or a lower one;
* no import cycle, between layers or between the modules of one layer;
* no private name (leading underscore) is imported from another module;
* no module is over 500 lines, except the ones listed with their reason.

Failures name the module, the line and the offending import.
"""
import ast
import os
from collections import defaultdict

import pytest

ROOT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "core_se3")

# bottom to top; a module's layer is that of its first package below core_se3 (or its own name)
LAYERS = ["errors", "registry", "backend", "lie", "kernels", "mesh", "fem", "assembly", "model", "results", "solvers", "parallel", "io", "design", "scenario",
          "control", "catalogue", "cli", "__main__", "__init__"]

LONG_MODULES = {}     # module -> why it may exceed 500 lines (none today)


def _modules():
    out = {}
    for dirpath, _, files in os.walk(ROOT):
        for f in files:
            if f.endswith(".py"):
                path = os.path.join(dirpath, f)
                rel = os.path.relpath(path, os.path.dirname(ROOT))[:-3].replace(os.sep, ".")
                if rel.endswith(".__init__"):
                    rel = rel[: -len(".__init__")]
                out[rel] = path
    return out


MODULES = _modules()


def _layer(mod):
    parts = mod.split(".")
    if len(parts) == 1:                       # core_se3 itself (its __init__)
        return LAYERS.index("__init__")
    return LAYERS.index(parts[1])


def _resolve(mod, node):
    """Absolute module names a core_se3 import statement refers to (with the imported names)."""
    pkg = mod if MODULES[mod].endswith("__init__.py") else mod.rsplit(".", 1)[0]
    if isinstance(node, ast.Import):
        return [(a.name, None) for a in node.names if a.name.split(".")[0] == "core_se3"]
    if node.level:
        base = pkg.split(".")
        base = base[: len(base) - node.level + 1]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    if target.split(".")[0] != "core_se3":
        return []
    out = []
    for a in node.names:
        sub = f"{target}.{a.name}"
        out.append((sub, None) if sub in MODULES else (target, a.name))
    return out


def _imports():
    edges = []
    for mod, path in MODULES.items():
        with open(path, encoding="utf-8") as fh:
            tree = ast.parse(fh.read(), path)
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for target, name in _resolve(mod, node):
                    edges.append((mod, target, name, node.lineno))
    return edges


EDGES = _imports()


def test_layers_import_only_downward():
    bad = [f"{m} (layer {LAYERS[_layer(m)]}) line {ln} imports {t} (layer {LAYERS[_layer(t)]})"
           for m, t, _, ln in EDGES if t in MODULES and _layer(t) > _layer(m)]
    assert not bad, "upward imports:\n" + "\n".join(bad)


def test_no_import_cycles():
    graph = defaultdict(set)
    for m, t, _, _ in EDGES:
        if t in MODULES and t != m and not m.startswith(t + ".") and not (
                MODULES[m].endswith("__init__.py") and t.startswith(m + ".")):
            graph[m].add(t)
    state, stack, cycles = {}, [], []

    def visit(v):
        state[v] = 1
        stack.append(v)
        for w in sorted(graph[v]):
            if state.get(w) == 1:
                cycles.append(stack[stack.index(w):] + [w])
            elif w not in state:
                visit(w)
        stack.pop()
        state[v] = 2

    for v in sorted(MODULES):
        if v not in state:
            visit(v)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_no_private_name_crosses_a_module():
    bad = [f"{m} line {ln} imports {name} from {t}" for m, t, name, ln in EDGES
           if name and name.startswith("_") and t != m]
    assert not bad, "private names used across modules:\n" + "\n".join(bad)


@pytest.mark.parametrize("mod", sorted(MODULES))
def test_module_size(mod):
    with open(MODULES[mod], encoding="utf-8") as fh:
        n = sum(1 for _ in fh)
    assert n <= 500 or mod in LONG_MODULES, f"{mod} has {n} lines (limit 500; split it or list it with a reason)"


def test_the_scan_sees_the_imports():
    """Negative control: the scanner finds known downward imports and would flag an upward one."""
    assert ("core_se3.model.problem", "core_se3.assembly", "Assembler") in {(m, t, n) for m, t, n, _ in EDGES}
    assert _layer("core_se3.cli") > _layer("core_se3.model.problem") > _layer("core_se3.lie")
