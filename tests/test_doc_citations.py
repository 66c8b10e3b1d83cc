"""Nothing in ``docs/``, the README or a docstring cites a repository file that is not there.

Scanned: every Markdown file under ``docs/`` and ``README.md``, and every Python file of
``jointdb/``, ``bench/``, ``tests/`` and ``fixtures/`` (docstrings and comments alike). A citation is
a path that starts with one of the repository's top-level folders (``docs/``, ``bench/``,
``tests/``, ``jointdb/``, ``fixtures/``, ``migrations/``) and names a file by its extension or
a folder by a trailing slash; a relative Markdown link target (``[text](validation/x.md)``) is
resolved against the page that holds it; a ``*.md`` file named bare (``api-contracts.md``) must
exist somewhere in the repository; ``:mod:`jointdb.x``` must name an importable module.
Patterns (``*``, ``<name>``, ``{a,b}``) are resolved as globs where they can be, and skipped
where they cannot.
"""

from __future__ import annotations

import functools
import importlib.util
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TOP = ("docs", "bench", "tests", "jointdb", "fixtures", "migrations")
EXTENSIONS = ("md", "py", "json", "uff", "csv", "h5", "hdf5", "sqlite", "toml", "ini", "html", "js", "css",
              "png", "svg", "txt", "mako", "cfg", "yaml", "yml", "sh")
PATH = re.compile(r"(?<![\w./~-])((?:%s)/[\w./*<>{},-]*)" % "|".join(TOP))
MD_LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
BARE_MD = re.compile(r"(?<![\w./-])([\w-]+\.md)\b")
MOD_REF = re.compile(r":mod:`~?(jointdb(?:\.\w+)*)`")


@functools.cache
def _markdown_names() -> frozenset[str]:
    """The names of the repository's Markdown files (walked once, the virtual environment left out)."""
    return frozenset(p.name for p in _repo_files("*.md"))


def _repo_files(pattern: str) -> list[Path]:
    """Files of the repository matching ``pattern``, without descending into ``.venv``, ``.git`` or build folders."""
    out = []
    for top in REPO.iterdir():
        if top.name in (".venv", ".git", "build", "node_modules") or top.name.endswith(".egg-info"):
            continue
        if top.is_dir():
            out += top.rglob(pattern)
        elif top.match(pattern):
            out.append(top)
    return out


def _sources() -> list[Path]:
    files = [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]
    for top in ("jointdb", "bench", "tests", "fixtures"):
        files += sorted(p for p in (REPO / top).rglob("*.py") if ".venv" not in p.parts)
    return [f for f in files if f != Path(__file__).resolve()]  # this file cites missing files on purpose


def _cited_paths(text: str) -> list[str]:
    """Repository paths cited in ``text``: a file by its extension, or a folder by a trailing slash."""
    out = []
    for raw in PATH.findall(text):
        path = raw.rstrip(".,;:)")
        if path.endswith("/") or re.search(r"\.(%s)$" % "|".join(EXTENSIONS), path):
            out.append(path)
    return out


def _exists(path: str, base: Path = REPO) -> bool:
    if "{" in path:  # a brace list: each alternative must exist
        head, rest = path.split("{", 1)
        if "}" not in rest:
            return True
        alts, tail = rest.split("}", 1)
        return all(_exists(head + alt + tail, base) for alt in alts.split(","))
    if "<" in path:  # a placeholder: some file must match with it as a wildcard
        path = re.sub(r"<[^>]*>", "*", path)
    if "*" in path:
        return any(base.glob(path.rstrip("/")))
    return (base / path).exists()


def _problems(source: Path) -> list[str]:
    return _problems_in(source.read_text(encoding="utf-8"), str(source.relative_to(REPO)), source)


def _problems_in(text: str, rel: str, source: Path) -> list[str]:
    """The broken citations of ``text`` (the contents of ``source``, named ``rel`` in the messages)."""
    problems = [f"{rel}: cites {p}, which is not in the repository" for p in _cited_paths(text) if not _exists(p)]
    if source.suffix == ".md":
        for target in MD_LINK.findall(text):
            if "://" in target or target.startswith(("mailto:", "/")):
                continue
            if not _exists(target, source.parent):
                problems.append(f"{rel}: links to {target}, which is not in the repository")
    markdown_names = _markdown_names()
    for m in BARE_MD.finditer(text):
        name = m.group(1)
        if re.search(r"--[\w-]+[ =]$", text[max(0, m.start() - 40):m.start()]):
            continue  # an output file named on a command line (--markdown out.md), not a citation
        if name not in markdown_names:
            problems.append(f"{rel}: cites {name}, which is not in the repository")
    for module in MOD_REF.findall(text):
        if not _importable(module):
            problems.append(f"{rel}: cites module {module}, which does not exist")
    return problems


def _importable(dotted: str) -> bool:
    """A module, or a name defined in one (``:mod:`` is sometimes used for a name inside a module)."""
    try:
        if importlib.util.find_spec(dotted) is not None:
            return True
    except ModuleNotFoundError:
        return False
    parent, _, name = dotted.rpartition(".")
    try:
        return hasattr(importlib.import_module(parent), name)
    except ImportError:
        return False


@pytest.mark.parametrize("source", _sources(), ids=lambda p: str(p.relative_to(REPO)))
def test_cited_files_exist(source):
    problems = _problems(source)
    assert not problems, "\n".join(problems)


def test_the_check_finds_a_missing_file():
    """The scanner is not vacuous: a page citing a file that is not there, a dead relative link, a bare
    contracts file and a missing module are each reported; the real files they sit beside are not."""
    text = ("See docs/theory.md and jointdb/no_such_module.py, [a link](validation/nowhere.md), "
            "[a good one](validation/performance.md), the api-contracts.md notes, :mod:`jointdb.store._no_such` "
            "and :mod:`jointdb.store`; fixtures/models/ is fine, --markdown out.md is an output.\n")
    problems = _problems_in(text, "docs/probe.md", REPO / "docs" / "probe.md")
    assert len(problems) == 4, problems
    for missing in ("jointdb/no_such_module.py", "validation/nowhere.md", "api-contracts.md", "jointdb.store._no_such"):
        assert any(missing in p for p in problems), (missing, problems)
    assert not any("docs/theory.md" in p or "fixtures/models/" in p for p in problems)
