"""Every Sphinx cross-reference in the package's docstrings names something that exists.

A reference ``:func:`x.y``` (also ``:class:``, ``:meth:``, ``:mod:``, ``:data:``, ``:attr:``,
``:exc:``; a leading ``~`` or ``.`` only shortens how it is shown) resolves as a dotted path
from an importable module (``demseis.seismic.PropertyModel``, ``numpy.random.Generator``), or
as a name of the module whose docstring holds it (``:func:`label_maps``` in the module that
defines or imports it), or of the class whose docstring or method holds it.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import re
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "demseis"
ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj):`([^`<>]+?)`")


def _module_name(path: Path) -> str:
    rel = path.relative_to(PKG.parent).with_suffix("")
    parts = list(rel.parts[:-1]) if rel.name == "__init__" else list(rel.parts)
    return ".".join(parts)


def _docstrings(tree: ast.Module) -> list[tuple[str | None, str]]:
    """(enclosing class name or None, docstring) of the module and every class and function."""
    out: list[tuple[str | None, str]] = []
    if ast.get_docstring(tree):
        out.append((None, ast.get_docstring(tree)))

    def walk(node: ast.AST, cls: str | None) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ClassDef):
                if ast.get_docstring(child):
                    out.append((child.name, ast.get_docstring(child)))
                walk(child, child.name)
            elif isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                if ast.get_docstring(child):
                    out.append((cls, ast.get_docstring(child)))
                walk(child, cls)

    walk(tree, None)
    return out


def _resolve_dotted(path: str) -> bool:
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for name in parts[cut:]:
                obj = getattr(obj, name)
        except AttributeError:
            return False
        return True
    return False


def _resolve(ref: str, module: object, cls: str | None) -> bool:
    ref = ref.strip().lstrip("~.").removesuffix("()")
    if _resolve_dotted(ref):
        return True
    scopes = [module]
    if cls is not None and hasattr(module, cls):
        scopes.insert(0, getattr(module, cls))
    for scope in scopes + [builtins]:
        obj = scope
        try:
            for name in ref.split("."):
                obj = getattr(obj, name)
        except AttributeError:
            continue
        return True
    return False


def _refs() -> list[tuple[str, str, str | None]]:
    out = []
    for path in sorted(PKG.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        tree = ast.parse(path.read_text(), str(path))
        for cls, doc in _docstrings(tree):
            out += [(_module_name(path), m.group(1), cls) for m in ROLE.finditer(doc)]
    return out


def test_there_are_references_to_check():
    assert len(_refs()) > 100


def test_every_docstring_reference_resolves():
    bad = []
    for module_name, ref, cls in _refs():
        module = importlib.import_module(module_name)
        if not _resolve(ref, module, cls):
            bad.append(f"{module_name}: `{ref}`" + (f" (in class {cls})" if cls else ""))
    assert not bad, "docstring references to nothing:\n" + "\n".join(sorted(set(bad)))


@pytest.mark.parametrize("ref, ok", [
    ("demseis.seismic.PropertyModel", True),
    ("~demseis.types.Grid.covering", True),
    ("demseis.seismic.grid.Grid", False),
    ("demseis.dem.types.Snapshot", False),
    ("numpy.random.Generator", True),
    ("KeyError", True),
])
def test_the_resolver_is_not_vacuous(ref, ok):
    assert _resolve(ref, importlib.import_module("demseis.types"), None) is ok
