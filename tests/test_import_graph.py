"""The package's import graph has no cycle through more than two modules (issue 33: a 13-module circle ran through the
map registry, ``maps.py`` ↔ ``backlund``, ``gaudin``, ``exact``, ``flows``, ``midpoint``).  The graph is computed
from the sources' AST: an edge ``a → b`` for every ``import``/``from ... import`` of a ``jetgaudin`` module that runs
when ``a`` is imported (module level, including ``try``/``if`` blocks, but not inside functions or classes, whose
imports run on use, nor under ``if TYPE_CHECKING:``), a package standing for its ``__init__``: the circles that
decide whether a module can be imported on its own and in which order the package loads.  A second graph adds the
imports inside functions (``import_graph(functions=True)``): no circle through more than two files there either."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "jetgaudin"
PKG = "jetgaudin"


def _modules() -> dict[str, Path]:
    out = {}
    for p in SRC.rglob("*.py"):
        parts = p.relative_to(SRC.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = p
    return out


def _resolve(mod: str, is_pkg: bool, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _import_time_nodes(body):
    """The statements of ``body`` that run at import time, recursively (not function or class bodies, not the body of
    ``if TYPE_CHECKING:``)."""
    for node in body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            continue
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            yield from _import_time_nodes(node.orelse)
            continue
        yield node
        for field in ("body", "orelse", "finalbody", "handlers"):
            yield from _import_time_nodes(getattr(node, field, []) or [])


def _run_nodes(body):
    """Every statement of ``body`` that may ever run, at any depth (function and class bodies included), except the
    body of ``if TYPE_CHECKING:`` (it never runs)."""
    for node in body:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            yield from _run_nodes(node.orelse)
            continue
        yield node
        for name in ("body", "orelse", "finalbody", "handlers", "cases"):
            yield from _run_nodes(getattr(node, name, []) or [])


def import_graph(lazy: bool = False, functions: bool = False) -> dict[str, set[str]]:
    """The import-time graph (module docstring); ``functions=True``: with the imports inside functions too (they run on
    use), not those under ``if TYPE_CHECKING:``; ``lazy=True``: every import at any depth (``TYPE_CHECKING``
    included)."""
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}

    def known(name: str) -> str | None:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name or None

    for mod, path in mods.items():
        is_pkg = path.name == "__init__.py"
        tree = ast.parse(path.read_text())
        nodes = ast.walk(tree) if lazy else _run_nodes(tree.body) if functions else _import_time_nodes(tree.body)
        for node in nodes:
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(mod, is_pkg, node)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base for a in node.names]
            for t in targets:
                if t.split(".")[0] == PKG and (k := known(t)) and k != mod:
                    graph[mod].add(k)
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's algorithm (iterative): the strongly connected components."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == v:
                            break
                    out.append(sorted(comp))
    return out


def test_the_tarjan_helper_finds_cycles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a", "e"}, "e": {"d"}, "f": set()}
    assert sorted(map(tuple, strongly_connected(g))) == [("a", "b", "c"), ("d", "e"), ("f",)]


def test_no_import_cycle_through_more_than_two_modules():
    graph = import_graph()
    assert len(graph) > 80 and "jetgaudin.maps" in graph and "jetgaudin.backlund" in graph["jetgaudin.ensemble"] | {
        "jetgaudin.backlund"}
    big = [c for c in strongly_connected(graph) if len(c) > 2]
    assert not big, "import cycles through more than two modules:\n" + "\n".join(" <-> ".join(c) for c in big)


def test_no_circle_through_more_than_two_files_function_level_imports_included():
    """Issue 33: "no import circle larger than two files", counting the imports inside functions (they run on use: a
    circle through them decides what a module drags in and hides layering mistakes).  ``jetgaudin.gaudin`` had a
    7-module circle (``model`` → ``maps``, ``_one_point``, ``sun`` on use; ``sun`` → ``sun_maps``, ``sun_exact``),
    broken by the registry of ``gaudin._model_map``; ``plotting`` a 4-module one (``_files`` ↔ ``_chains``,
    ``_compare``, ``_ensemble`` through ``save_figure``), broken by moving it below them (``plotting._save``)."""
    graph = import_graph(functions=True)
    assert "jetgaudin.gaudin.sun_maps" in graph["jetgaudin.gaudin.sun_exact"]  # the walk reaches module level
    assert "jetgaudin.lax" in graph["jetgaudin.gaudin.model"]  # and inside methods (model.lax_matrix)
    big = [c for c in strongly_connected(graph) if len(c) > 2]
    assert not big, "import cycles through more than two files:\n" + "\n".join(" <-> ".join(c) for c in big)


def test_the_function_level_walk_sees_nested_imports_and_skips_type_checking(tmp_path):
    """The walk that the test above relies on: an import in a method of a class, in a nested ``try``/``with``, is an
    edge; one under ``if TYPE_CHECKING:`` is not (a planted 3-cycle through a method is found)."""
    src = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import jetgaudin.c\n"
        "class A:\n    def f(self):\n        try:\n            with open('x'):\n                from . import b\n"
        "        except OSError:\n            pass\n"
    )
    nodes = list(_run_nodes(ast.parse(src).body))
    names = [n.module if isinstance(n, ast.ImportFrom) else n.names[0].name
             for n in nodes if isinstance(n, ast.Import | ast.ImportFrom)]
    assert names == ["typing", None] and sum(isinstance(n, ast.ImportFrom) and n.level == 1 for n in nodes) == 1
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}}
    assert [c for c in strongly_connected(g) if len(c) > 2] == [["a", "b", "c"]]


def test_the_map_interface_imports_none_of_its_implementations():
    """Lazy imports included, ``jetgaudin.maps`` is in no cycle: the registry is filled by the implementing modules
    (imported by name when a description is read), so the 13-module circle through it (``maps`` ↔ ``backlund``,
    ``gaudin``, ``exact``, ``flows``, ``midpoint``) is gone."""
    graph = import_graph(lazy=True)
    comp = next(c for c in strongly_connected(graph) if "jetgaudin.maps" in c)
    assert comp == ["jetgaudin.maps"], comp
    from jetgaudin.maps import map_from_description

    assert map_from_description({"kind": "two_point", "b": 1.0, "eta": [5.0, 0.1], "branch": "default"}) is not None


SYSTEM_LAYER = ("algebra", "lax", "spectral", "hamiltonians", "systems", "canonical", "lie")


def test_the_system_layer_imports_only_the_system_layer_lazily_included():
    """The layers of ``docs/architecture.md``: the system layer imports nothing below it, not even inside functions
    (the top's one-site-model views, ``GaudinTop.model`` and ``IntegralHamiltonian.as_model``, reach
    ``jetgaudin.gaudin`` by name, as the map registry does), so no import circle runs through it."""
    graph = import_graph(lazy=True)
    allowed = {f"{PKG}.{m}" for m in SYSTEM_LAYER} | {f"{PKG}._errors", f"{PKG}._validate"}
    for m in SYSTEM_LAYER:
        assert graph[f"{PKG}.{m}"] <= allowed, (m, sorted(graph[f"{PKG}.{m}"] - allowed))
