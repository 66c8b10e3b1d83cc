"""No import cycles between the modules of ``jointdb/``, and a declared layer order
that no import breaks (issue 23).

The graph is read from the source with :mod:`ast`, not by importing: every
``import`` / ``from ... import`` counts wherever it stands (module level, inside a
function, under ``TYPE_CHECKING``), so a cycle cannot be hidden by moving an import
into a function. An edge goes to the module named, or to the submodule when a name
imported from a package is itself a module (``from jointdb.fe import _model``).

The layers, lowest first (:data:`LAYER_RANK`): the numeric core; files, wire formats
and the store (the HTTP client is a store implementation and sits there too); the
application layer (the use cases); the shells, the CLI and the HTTP service. An
import may go down, or stay within one layer; it never goes up, and the two shells
never import each other (same rank, different layer).
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


#: Rank of each layer: an import goes to a lower rank or stays in its own layer.
#: ``cli`` and ``server`` share the top rank, so an import between them is refused.
LAYER_RANK = {"core": 0, "store": 1, "application": 2, "cli": 3, "server": 3}

#: Module prefix -> layer. A module belongs to its longest matching prefix (the prefix
#: itself or a module below it); the package root ``jointdb`` is matched exactly only.
#: Every module must match one entry (test_every_module_has_a_layer).
LAYERS = {
    # numeric core: arrays in, arrays out; no files beyond the model/stack readers
    "jointdb": "core",  # the package root (__version__, FRF re-export)
    "jointdb.frf": "core",
    "jointdb.errors": "core",
    "jointdb._limits": "core",
    "jointdb._jsonfile": "core",  # the bounded JSON reader fe._modelfile uses
    "jointdb.fe": "core",
    "jointdb.coupling": "core",
    "jointdb.modal": "core",
    "jointdb.stack": "core",
    "jointdb.stability": "core",
    "jointdb.diagnose": "core",
    "jointdb.diagnose_bench": "core",
    # files, wire formats, the store and its HTTP implementation
    "jointdb.io": "store",
    "jointdb.store": "store",
    "jointdb.migrations": "store",  # the Alembic environment, shipped in the wheel as jointdb/migrations
    "jointdb.client": "store",  # the store over HTTP: imports no server code
    "jointdb.plots": "store",
    "jointdb.schemas": "store",
    "jointdb._output": "store",  # tables / JSON on stdout, atomic output files
    "jointdb._mdtable": "store",
    # application layer: the use cases (a campaign reads its files and identifies)
    "jointdb.usecases": "application",  # the application package: the use cases the shells call
    "jointdb.campaign": "application",
    "jointdb.jobs": "application",  # the job queue (procrastinate / in-process) and what each kind of job runs
    "jointdb._journey": "application",
    "jointdb._journey_band": "application",
    "jointdb._examples": "application",
    # the shells
    "jointdb.cli": "cli",
    "jointdb.__main__": "cli",
    "jointdb.server": "server",
}

#: Imports allowed to break the layer order, each ``(importer, imported)``: none. (The last
#: two, the server's routes importing the CLI's joint-file reader, went when the catalogue
#: path moved into :mod:`jointdb.usecases`.) An entry must name an import that exists: the
#: test fails when a listed import is gone, so this list cannot go stale.
KNOWN_LAYER_BREAKS: set[tuple[str, str]] = set()


def layer_of(module: str) -> str | None:
    """The layer of ``module`` from :data:`LAYERS` (None when no entry matches)."""
    if module == "jointdb":
        return LAYERS["jointdb"]
    best = max((p for p in LAYERS if p != "jointdb" and (module == p or module.startswith(p + "."))),
               key=len, default=None)
    return None if best is None else LAYERS[best]


def layer_breaks(graph: dict[str, set[str]]) -> set[tuple[str, str]]:
    """The imports ``(importer, imported)`` that go up a layer or across between the shells."""
    out = set()
    for name, targets in graph.items():
        mine = layer_of(name)
        for target in targets:
            theirs = layer_of(target)
            if theirs != mine and LAYER_RANK[theirs] >= LAYER_RANK[mine]:
                out.add((name, target))
    return out


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


def test_every_module_has_a_layer():
    loose = sorted(m for m in import_graph() if layer_of(m) is None)
    assert not loose, f"modules with no layer; add them to LAYERS in this file: {loose}"


def test_the_layer_rule_refuses_up_and_across():
    fake = {
        "jointdb.frf": {"jointdb.store._db"},                  # core -> store: up
        "jointdb.store._db": {"jointdb.frf", "jointdb.io._hdf5"},  # down, and within its layer
        "jointdb.client": {"jointdb.server._deps"},            # store -> shell: up
        "jointdb.cli._serve": {"jointdb.server._logging", "jointdb.store"},  # across the shells
        "jointdb.server._app": {"jointdb.campaign._run"},      # shell -> application: down
    }
    assert layer_breaks(fake) == {("jointdb.frf", "jointdb.store._db"), ("jointdb.client", "jointdb.server._deps"),
                                  ("jointdb.cli._serve", "jointdb.server._logging")}


def test_no_import_breaks_the_layer_order():
    new = layer_breaks(import_graph()) - KNOWN_LAYER_BREAKS
    assert not new, "imports against the layer order (core -> store/io -> application -> cli | server): " + "; ".join(
        f"{a} ({layer_of(a)}) -> {b} ({layer_of(b)})" for a, b in sorted(new))


def test_every_allow_listed_layer_break_still_exists():
    gone = KNOWN_LAYER_BREAKS - layer_breaks(import_graph())
    assert not gone, "these allow-listed layer breaks are gone; remove them from KNOWN_LAYER_BREAKS in this file: " + (
        "; ".join(f"{a} -> {b}" for a, b in sorted(gone)))


def test_the_client_and_its_wire_format_load_no_server_library():
    """The client decodes FRFs with :mod:`jointdb.io`; neither pulls in FastAPI or the server."""
    import subprocess
    import sys

    code = ("import sys, jointdb.client\nfrom jointdb.io import frf_from_json, frf_json\n"
            "print(','.join(m for m in ('fastapi', 'starlette', 'uvicorn', 'jointdb.server') if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"the client loads {out.stdout.strip()}"
