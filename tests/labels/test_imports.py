"""The modules of demseis.labels import each other one way, and at module level.

No module imports (even inside a function) a module that imports it back, the package's
``__init__`` included. A function may import only a heavy optional dependency (matplotlib,
torch), so that every other dependency is visible at the top of the module.
"""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "demseis" / "labels"
NAME = "demseis.labels"
#: what a function may import (heavy optional dependencies, imported only where used)
LOCAL_OK = {"matplotlib", "torch"}


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted(PKG.glob("*.py")):
        out[NAME if p.stem == "__init__" else f"{NAME}.{p.stem}"] = p
    return out


def _resolve(mod: str, name: str | None) -> str | None:
    """The labels module an import reaches: ``from demseis.labels import x`` reaches the
    submodule x where there is one, else the package."""
    if name is not None and mod == NAME and (PKG / f"{name}.py").exists():
        return f"{NAME}.{name}"
    if mod == NAME or mod.startswith(NAME + "."):
        return mod
    return None


def _imports(path: Path) -> list[tuple[str, bool, int]]:
    """(module, imported inside a function or class, line) of every import of ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    top = {id(n) for n in tree.body}
    out = []
    for node in ast.walk(tree):
        local = id(node) not in top
        if isinstance(node, ast.Import):
            out += [(a.name, local, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            if node.level:
                raise AssertionError(f"{path.name}:{node.lineno}: relative import")
            if node.module == NAME:
                out += [(f"{NAME}.{a.name}" if (PKG / f"{a.name}.py").exists() else NAME,
                         local, node.lineno) for a in node.names]
            else:
                out.append((node.module, local, node.lineno))
    return out


def _graph() -> dict[str, set[str]]:
    mods = _modules()
    graph = {}
    for me, path in mods.items():
        graph[me] = set()
        for mod, _, _ in _imports(path):
            target = _resolve(mod, None)
            if target in mods and target != me:
                graph[me].add(target)
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}  # 1: on the path, 2: done
    path: list[str] = []

    def visit(u: str) -> list[str] | None:
        state[u] = 1
        path.append(u)
        for v in sorted(graph[u]):
            if state.get(v) == 1:
                return path[path.index(v):] + [v]
            if v not in state and (found := visit(v)):
                return found
        path.pop()
        state[u] = 2
        return None

    for u in sorted(graph):
        if u not in state and (found := visit(u)):
            return found
    return None


def test_no_import_cycles():
    cycle = _cycle(_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_the_cycle_check_finds_a_cycle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None
    # the package front door counts: a module importing it is a cycle
    graph = _graph()
    graph[f"{NAME}.traces"].add(NAME)
    assert _cycle(graph) is not None


def test_functions_import_only_heavy_optional_dependencies():
    bad = [f"{path.name}:{line} imports {mod} inside a function"
           for path in _modules().values() for mod, local, line in _imports(path)
           if local and mod.split(".")[0] not in LOCAL_OK]
    assert not bad, "\n".join(bad)
