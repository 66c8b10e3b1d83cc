"""No import cycles between the modules of ``jointdb/`` (issue 23).

The graph is read from the source with :mod:`ast`, not by importing: every
``import`` / ``from ... import`` counts wherever it stands (module level, inside a
function, under ``TYPE_CHECKING``), so a cycle cannot be hidden by moving an import
into a function. An edge goes to the module named, or to the submodule when a name
imported from a package is itself a module (``from jointdb.fe import _model``).
"""

from __future__ import annotations

import ast
from pathlib import Path

import jointdb

PACKAGE = Path(jointdb.__file__).resolve().parent

#: Cycles known today, each as the set of modules of one strongly connected component.
#: None: the store's two (repository <-> bundle/maintenance/query, nearest <-> qcache) went
#: with the store protocol (issue 23, step 2). The test fails when a listed cycle is gone
#: or has changed, so this list cannot go stale.
KNOWN_CYCLES: set[frozenset[str]] = set()


def _modules(root: Path) -> dict[str, Path]:
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _imported(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The jointdb modules ``name`` (at ``path``) imports, anywhere in its body."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in modules else target)
    return {m for m in found if m in modules and m != name}


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """``{module: modules it imports}`` over the package at ``root``."""
    modules = _modules(root)
    return {name: _imported(name, path, modules) for name, path in modules.items()}


def cycles(graph: dict[str, set[str]]) -> set[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: set[frozenset[str]] = set()
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.add(frozenset(component))
    return found


def _show(cycle: frozenset[str]) -> str:
    return " ↔ ".join(sorted(cycle))


def test_the_graph_sees_module_and_function_level_imports():
    graph = import_graph()
    assert "jointdb.frf" in graph["jointdb.fe._mesh"]                  # module level
    assert "jointdb.fe._synthesis" in graph["jointdb.fe._model"]
    assert "jointdb.diagnose.physics.amplitude" in graph["jointdb.diagnose.physics"]   # submodule by name
    fake = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert cycles(fake) == {frozenset("abc")}


def test_no_new_import_cycle():
    new = cycles(import_graph()) - KNOWN_CYCLES
    assert not new, "import cycles between modules of jointdb/: " + "; ".join(map(_show, sorted(new, key=sorted)))


def test_every_allow_listed_cycle_still_exists():
    gone = KNOWN_CYCLES - cycles(import_graph())
    assert not gone, (
        "these allow-listed cycles are gone or have changed; update KNOWN_CYCLES in this file: "
        + "; ".join(map(_show, sorted(gone, key=sorted)))
    )
