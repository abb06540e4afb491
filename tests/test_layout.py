"""The import graph of the package runs one way, has no cycles, and nothing imports ``tests``.

cli -> plotting / api -> generator | learning -> evaluation -> datasets -> dem | seismic | labels
-> types / parameters / schema -> registry -> errors | interrupts (standard library only). A stage (dem, seismic, labels) never
imports ``datasets`` and reaches another stage only through its package (``from demseis.seismic
import rasterise``), never its modules. ``demseis_dev`` (benchmarks, calibration, measures, toy
inputs), beside the package and not installed, may import any of these, but no module of the
package imports it. No module imports, even indirectly, a module that imports it. Every import counts, including those inside functions.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "demseis"
STAGES = ("dem", "seismic", "labels")

#: rank of each top-level part of the package: a module may import only parts of lower or equal
#: rank (equal only within the same part)
RANK = {
    "errors": 0, "interrupts": 0,
    "registry": 1,
    "types": 2, "parameters": 2, "schema": 2,
    "dem": 3, "seismic": 3, "labels": 3,
    "datasets": 4,
    "evaluation": 5,
    "generator": 6, "learning": 6,
    "api": 7, "plotting": 7, "survey_fit": 7,
    "cli": 8, "__main__": 9,
}
#: names of the root package any module may import (the root module imports nothing heavy)
ROOT_NAMES = {"__version__", "DemseisError"}


def _part(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _imports(path: Path) -> list[tuple[str, list[str], int]]:
    """(module, imported names, line) of every import in ``path``, relative ones resolved."""
    return _imports_in(path, ROOT)


def _module_level_import_lines(path: Path) -> set[int]:
    """Lines of the imports that run when ``path`` is imported (not inside a function)."""
    return {line for _, _, line in _imports_in(path, ROOT, top_level_only=True)}


def _module_files() -> list[Path]:
    return sorted(p for p in PKG.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_part_has_a_rank():
    parts = {p.relative_to(PKG).parts[0].removesuffix(".py") for p in _module_files()}
    parts.discard("__init__")
    assert parts <= set(RANK), f"give these parts a rank in tests/test_layout.py: {parts - set(RANK)}"


def test_imports_run_one_way():
    bad = []
    for path in _module_files():
        rel = path.relative_to(PKG)
        if rel.parts == ("__init__.py",):
            continue  # the front door: checked by test_root_imports_lazily
        me = rel.parts[0].removesuffix(".py")
        for mod, names, line in _imports(path):
            if mod == "demseis":
                # `from demseis import x`: only the light root names, or a subpackage of lower rank
                for n in names:
                    if n in ROOT_NAMES:
                        continue
                    if n not in RANK or (RANK[n] >= RANK[me] and n != me):
                        bad.append(f"{rel}:{line} imports demseis.{n}")
                continue
            if not mod.startswith("demseis."):
                continue
            other = _part(mod)
            if other == me:
                continue
            if me in STAGES and other in STAGES:
                if mod != f"demseis.{other}":
                    bad.append(f"{rel}:{line}: stage {me} imports {mod}, an internal of stage "
                               f"{other}")
            elif RANK.get(other, 99) >= RANK[me]:
                bad.append(f"{rel}:{line} ({me}, rank {RANK[me]}) imports {mod} "
                           f"({other}, rank {RANK.get(other)})")
    assert not bad, "imports against the data flow:\n" + "\n".join(bad)


#: the layers of ``demseis/generator``: a module may import its own layer and those below it
GENERATOR_LAYERS = {"config": 0, "engines": 1, "render": 2, "sweep": 3}


def _generator_layer(module: str) -> str | None:
    """The generator layer of a ``demseis.generator...`` module name, None for the package."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[:2] == ["demseis", "generator"] else None


def test_generator_layers_run_one_way():
    """config <- engines <- render <- sweep, every module of demseis/generator in a layer."""
    gen = PKG / "generator"
    bad = []
    for path in sorted(p for p in gen.rglob("*.py") if "__pycache__" not in p.parts):
        rel = path.relative_to(gen)
        if rel.parts == ("__init__.py",):
            continue
        me = rel.parts[0]
        if me not in GENERATOR_LAYERS:
            bad.append(f"demseis/generator/{rel.as_posix()} is in no layer")
            continue
        for mod, names, line in _imports(path):
            if mod == "demseis.generator":
                others = names  # from demseis.generator import <layer>
            elif mod.startswith("demseis.generator."):
                others = [_generator_layer(mod)]
            else:
                continue
            for other in others:
                if GENERATOR_LAYERS.get(other, 99) > GENERATOR_LAYERS[me]:
                    bad.append(f"demseis/generator/{rel.as_posix()}:{line} ({me}) imports {mod} "
                               f"({other})")
    assert not bad, "generator layers imported against their order:\n" + "\n".join(bad)


def _fake_package(tmp_path: Path, monkeypatch, files: dict[str, str]) -> None:
    """Write a fake ``demseis`` package of ``files`` (path below it -> source) under
    ``tmp_path`` and point the checks of this module at it."""
    fake = tmp_path / "demseis"
    for rel, source in {"__init__.py": "", **files}.items():
        (fake / rel).parent.mkdir(parents=True, exist_ok=True)
        (fake / rel).write_text(source)
    monkeypatch.setattr(f"{__name__}.PKG", fake)
    monkeypatch.setattr(f"{__name__}.ROOT", tmp_path)


def test_generator_layer_check_is_not_vacuous(tmp_path, monkeypatch):
    _fake_package(tmp_path, monkeypatch, {
        "generator/config/x.py": "from demseis.generator.render.section import render_run\n",
        "generator/render/y.py": "from demseis.generator.config import x\n",
        "generator/stray/z.py": ""})
    with pytest.raises(AssertionError) as err:
        test_generator_layers_run_one_way()
    msg = str(err.value)
    assert "config/x.py:1 (config) imports demseis.generator.render.section" in msg, msg
    assert "render/y.py" not in msg and "stray/z.py is in no layer" in msg, msg


def test_root_imports_lazily():
    """demseis/__init__.py imports nothing at import time but errors (the rest is lazy)."""
    tree = ast.parse((PKG / "__init__.py").read_text())
    top = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    mods = {n.module if isinstance(n, ast.ImportFrom) else n.names[0].name for n in top}
    assert mods <= {"__future__", "demseis.errors", "typing", "importlib"}, mods


def test_no_stage_imports_datasets():
    for stage in STAGES:
        for path in (PKG / stage).rglob("*.py"):
            for mod, names, line in _imports(path):
                assert not mod.startswith("demseis.datasets") and not (
                    mod == "demseis" and "datasets" in names), f"{path}:{line} imports {mod}"


def test_nothing_imports_tests():
    bad = []
    for folder in ("demseis", "benchmarks", "examples", "scripts"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for mod, _, line in _imports(path):
                if mod == "tests" or mod.startswith("tests."):
                    bad.append(f"{path.relative_to(ROOT)}:{line} imports {mod}")
    assert not bad, "\n".join(bad)


def test_package_never_imports_demseis_dev():
    """demseis_dev is not installed: an import of it anywhere in the package would fail for
    users (inside a function too)."""
    bad = [f"{path.relative_to(PKG)}:{line} imports {mod}"
           for path in _module_files() for mod, _names, line in _imports(path)
           if mod == "demseis_dev" or mod.startswith("demseis_dev.")]
    assert not bad, "demseis_dev reached from the package:\n" + "\n".join(bad)


def test_demseis_dev_check_is_not_vacuous(tmp_path, monkeypatch):
    """Eager and lazy imports of demseis_dev are both caught."""
    _fake_package(tmp_path, monkeypatch, {
        "generator/x.py": "def f():\n    from demseis_dev.toys import disk_pack\n",
        "cli/plots.py": "import demseis_dev.bench\n"})
    with pytest.raises(AssertionError) as err:
        test_package_never_imports_demseis_dev()
    assert "generator/x.py:2" in str(err.value) and "cli/plots.py:1" in str(err.value)


def test_demseis_dev_is_not_installed():
    """The distribution ships demseis and its subpackages only."""
    import tomllib

    find = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert find["packages"]["find"]["include"] == ["demseis", "demseis.*"]


def test_checker_catches_a_backward_import(tmp_path, monkeypatch):
    """The rank rule is not vacuous: a stage importing datasets is caught."""
    _fake_package(tmp_path, monkeypatch, {
        "seismic/x.py": ("from demseis.datasets import open_store\n"
                         "from demseis.labels.maps import label_maps\n")})
    try:
        test_imports_run_one_way()
    except AssertionError as exc:
        assert "imports demseis.datasets" in str(exc) and "internal of stage labels" in str(exc)
    else:
        raise AssertionError("a seismic -> datasets import passed the check")


def _module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts[:-1]) if rel.name == "__init__" else list(rel.parts)
    return ".".join(parts)


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """module -> the demseis modules it imports (``from pkg import sub`` counts as importing
    ``pkg.sub`` when ``sub`` is a module, else as importing ``pkg``)."""
    files = sorted(p for p in (root / "demseis").rglob("*.py") if "__pycache__" not in p.parts)
    modules = {_module_name(p, root) for p in files}
    graph: dict[str, set[str]] = {}
    for path in files:
        me = _module_name(path, root)
        edges = graph.setdefault(me, set())
        found = _imports_in(path, root)
        if me == "demseis":
            # the front door loads demseis.api on first attribute access, not at import, and
            # names it for type checkers only (test_root_imports_lazily): only the imports of
            # its body run
            body = {n.lineno for n in ast.parse(path.read_text()).body
                    if isinstance(n, (ast.Import, ast.ImportFrom))}
            found = [f for f in found if f[2] in body]
        for mod, names, _ in found:
            if mod not in modules:
                continue
            subs = [f"{mod}.{n}" for n in names if f"{mod}.{n}" in modules]
            edges.update(subs or [mod])
            if len(subs) < len(names):
                edges.add(mod)
        edges.discard(me)
    return graph


def _imports_in(path: Path, root: Path,
                top_level_only: bool = False) -> list[tuple[str, list[str], int]]:
    """(module, imported names, line) of every import in ``path`` (only the module-level ones
    with ``top_level_only``), relative ones resolved against ``root``."""
    rel = path.relative_to(root).with_suffix("")
    pkg_parts = list(rel.parts[:-1])
    out = []
    for node in _nodes(ast.parse(path.read_text(), str(path)), top_level_only):
        if isinstance(node, ast.Import):
            out += [(a.name, [], node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg_parts[: len(pkg_parts) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append((mod, [a.name for a in node.names], node.lineno))
    return out


def _nodes(tree: ast.Module, skip_functions: bool) -> list[ast.AST]:
    """Every node of ``tree``; with ``skip_functions``, not those inside a function body."""
    if not skip_functions:
        return list(ast.walk(tree))
    out: list[ast.AST] = []
    stack: list[ast.AST] = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        out.append(node)
        stack.extend(ast.iter_child_nodes(node))
    return out


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
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
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    cycles = import_cycles(import_graph())
    assert not cycles, "import cycles between demseis modules (imports inside functions " \
        "count):\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_cycle_checker_finds_a_hidden_cycle(tmp_path):
    """A cycle hidden by a function-local import, through a package's __init__, is found."""
    pkg = tmp_path / "demseis"
    (pkg / "labels").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "errors.py").write_text("")
    (pkg / "labels" / "__init__.py").write_text("from demseis.labels.maps import f\n")
    (pkg / "labels" / "maps.py").write_text("import numpy\nfrom demseis import errors\n"
                                             "def f():\n    from demseis.labels.traces import g\n")
    (pkg / "labels" / "traces.py").write_text("from demseis.labels import f\n")
    graph = import_graph(tmp_path)
    assert graph["demseis.labels.maps"] == {"demseis.errors", "demseis.labels.traces"}
    assert import_cycles(graph) == [["demseis.labels", "demseis.labels.maps",
                                     "demseis.labels.traces"]]
    (pkg / "labels" / "traces.py").write_text("from demseis import errors\n")
    assert import_cycles(import_graph(tmp_path)) == []


#: what a function may import: heavy or optional libraries, imported only where they are used
#: (each such import says why beside it)
LAZY_LIBRARIES = ("torch", "matplotlib", "xarray", "zarr", "dask", "distributed", "psutil",
                  "scipy.fft", "scipy.signal", "scipy.spatial")
#: package modules that load the package lazily: the front door (``import demseis`` loads no
#: NumPy), the CLI (``demseis --help`` loads no command), and two modules that stand for a
#: heavy library (the dask worker plugin, the Numba kernels of the semblance baseline)
LAZY_PACKAGE = {
    "__init__.py": None, "api.py": None, "cli/__init__.py": {"demseis.cli"},
    "generator/sweep/driver.py": {"demseis.generator.sweep.cluster"},
    "evaluation/baseline.py": {"demseis.evaluation._kernels"},
}
#: the most function-local imports the package may hold (each a heavy or optional library, or
#: one of the lazy package modules above)
MAX_FUNCTION_IMPORTS = 20


def _function_imports(path: Path) -> list[tuple[str, int]]:
    """(module, line) of every import inside a function of ``path``."""
    everything = {(m, line) for m, _, line in _imports(path)}
    top = _module_level_import_lines(path)
    return sorted((m, line) for m, line in everything if line not in top)


def _lazy_allowed(rel: Path, module: str) -> bool:
    if any(module == lib or module.startswith(lib + ".") for lib in LAZY_LIBRARIES):
        return True
    for where, modules in LAZY_PACKAGE.items():
        if rel.as_posix() == where or rel.parts[0] == where:
            return modules is None or module in modules
    return False


def test_functions_import_only_heavy_libraries():
    bad = []
    for path in _module_files():
        rel = path.relative_to(PKG)
        for module, line in _function_imports(path):
            if not _lazy_allowed(rel, module):
                bad.append(f"demseis/{rel}:{line} imports {module} inside a function")
    assert not bad, "move these imports to the top of their module:\n" + "\n".join(bad)


def test_few_function_local_imports():
    found = [f"demseis/{path.relative_to(PKG)}:{line} {module}" for path in _module_files()
             for module, line in _function_imports(path)]
    assert len(found) <= MAX_FUNCTION_IMPORTS, (
        f"{len(found)} imports inside functions (at most {MAX_FUNCTION_IMPORTS}): import at the "
        "top of the module, or once in a function that stands for the library:\n"
        + "\n".join(found))


def test_lazy_import_rule_is_not_vacuous():
    assert _lazy_allowed(Path("plotting.py"), "matplotlib.pyplot")
    assert _lazy_allowed(Path("cli/__init__.py"), "demseis.cli")
    assert not _lazy_allowed(Path("cli/store.py"), "demseis.datasets.read")
    assert not _lazy_allowed(Path("generator/sweep/driver.py"), "demseis.datasets")
    assert not _lazy_allowed(Path("labels/maps.py"), "demseis.labels.traces")
    assert not _lazy_allowed(Path("datasets/read.py"), "json")
