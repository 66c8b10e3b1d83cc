"""Every public parameter is documented (in the manner of python-control's ``test_docstrings.py``).

The public API is the ``__all__`` of each public package (:data:`docstring_helpers.PUBLIC_MODULES`):
its functions, its classes (their constructors) and the public methods of its classes (a
``typing.Protocol``'s methods are documented at their implementation, e.g. ``JointStore`` at
``Repository``, so the protocol's own stubs are not checked). For each,
every parameter of the signature must appear in the numpydoc ``Parameters`` section of its
docstring (a class may list its fields under ``Attributes``), and no listed parameter may be
missing from the signature — a renamed or removed argument cannot leave its documentation behind.

Callables written before this rule and not yet documented are listed by name in
``tests/docstring_backlog.txt``; the list can only shrink: a listed callable that is now
documented fails the test until its line is removed, and a callable that is not listed must be
documented in full. Package docstrings are catalogues: each public name appears in its package's
docstring.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import pytest

from docstring_helpers import (
    PUBLIC_MODULES,
    documented_parameters,
    parameter_problems,
    public_callables,
    sections,
)

BACKLOG_FILE = Path(__file__).with_name("docstring_backlog.txt")
BACKLOG = {line.split("#")[0].strip() for line in BACKLOG_FILE.read_text().splitlines()} - {""}
CALLABLES = list(public_callables())
NAMES = [name for name, _, _ in CALLABLES]

#: the main entry points: each has an Examples section (run by ``test_doctests``)
WITH_EXAMPLES = (
    "jointdb.coupling.couple",
    "jointdb.coupling.identify_planar_joint",
    "jointdb.coupling.identify_n_point_joints",
    "jointdb.coupling.identify_joint_matrix",
    "jointdb.FRF",
    "jointdb.fe.BeamModel",
    "jointdb.stack.predict_tool_tip",
    "jointdb.stack.tool_model",
    "jointdb.stability.milling_lobes_zoa",
    "jointdb.stability.milling_lobes_sd",
    "jointdb.stability.turning_lobes",
    "jointdb.store.Repository",
    "jointdb.store.Repository.nearest",
    "jointdb.store.Repository.interpolate",
    "jointdb.diagnose.diagnose",
)


@pytest.mark.parametrize("name,doc_obj,sig_obj", CALLABLES, ids=NAMES)
def test_every_parameter_is_documented(name, doc_obj, sig_obj):
    problems = parameter_problems(sig_obj, inspect.getdoc(doc_obj))
    if name in BACKLOG:
        assert problems, (f"{name} is documented now: remove its line from {BACKLOG_FILE.name} "
                          "so that it stays documented")
        pytest.xfail(f"in {BACKLOG_FILE.name}: " + "; ".join(problems))
    assert not problems, f"{name}: " + "; ".join(problems)


def _returns_a_value(func) -> bool:
    """True unless the signature says ``-> None`` (a function without annotation counts as returning)."""
    try:
        ann = inspect.signature(func).return_annotation
    except (TypeError, ValueError):
        return True
    return ann not in (None, "None")


@pytest.mark.parametrize("name,doc_obj,sig_obj", [c for c in CALLABLES if not inspect.isclass(c[1])],
                         ids=[n for n, d, _ in CALLABLES if not inspect.isclass(d)])
def test_every_returned_value_is_documented(name, doc_obj, sig_obj):
    """A public function or method that returns something says what, in a Returns (or Yields) section."""
    if not _returns_a_value(sig_obj):
        return
    found = sections(inspect.getdoc(doc_obj))
    assert "Returns" in found or "Yields" in found, f"{name}: no Returns section"


def test_backlog_names_only_public_callables():
    stale = sorted(BACKLOG - set(NAMES))
    assert not stale, f"{BACKLOG_FILE.name} lists names that are not public callables: {stale}"


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_main_entry_points_have_examples(name):
    obj = dict((n, d) for n, d, _ in CALLABLES)[name]
    assert ">>>" in sections(inspect.getdoc(obj)).get("Examples", ""), f"{name}: no Examples section with code"


@pytest.mark.parametrize("modname", PUBLIC_MODULES)
def test_package_docstring_is_a_catalogue(modname):
    """Each public name of a package is named in the package's docstring (scipy.signal style)."""
    module = importlib.import_module(modname)
    doc = module.__doc__ or ""
    missing = [name for name in module.__all__ if name not in doc]
    assert not missing, f"{modname}: the docstring does not name {missing}"


ROLE = re.compile(r":(?:func|class|data|meth):`~?([A-Za-z_]\w*)`")
ENTRY = re.compile(r"^ {2,}([A-Za-z_]\w*(?:, [A-Za-z_]\w*)*) +-- ", re.M)


def _catalogued_names(doc: str) -> set[str]:
    """Bare names the catalogue lists: ``:func:`name``` roles and ``   name -- text`` entries."""
    names = set(ROLE.findall(doc))
    for group in ENTRY.findall(doc):
        names |= {n.strip() for n in group.split(",")}
    return names


@pytest.mark.parametrize("modname", PUBLIC_MODULES)
def test_package_catalogue_lists_only_public_names(modname):
    """The other way round: what a package's catalogue lists is public there (in ``__all__``, or in one
    of its public submodules such as ``jointdb.schemas.model``) -- no stale or private entry."""
    module = importlib.import_module(modname)
    subs = [importlib.import_module(f"{modname}.{m.name}") for m in pkgutil.iter_modules(getattr(module, "__path__", []))
            if not m.name.startswith("_")]
    stale = sorted(n for n in _catalogued_names(module.__doc__ or "")
                   if n not in module.__all__ and not any(n in getattr(s, "__all__", vars(s)) for s in subs))
    assert not stale, f"{modname}: the docstring lists names that are not public there: {stale}"


def test_the_catalogue_check_sees_entries():
    doc = "Stores\n------\n   Repository   -- rows\n   a, b -- two\n:func:`open_store` and :mod:`x`\n"
    assert _catalogued_names(doc) == {"Repository", "a", "b", "open_store"}


# --- the check itself can fail -------------------------------------------------------------------


def _documented(freq, values, *, rtol=1e-9):
    """A well documented function.

    Parameters
    ----------
    freq : ndarray, shape (n_freq,)
        Frequencies [Hz].
    values : ndarray, shape (n_freq, n_out, n_in)
        Receptances [m/N].
    rtol : float, optional
        Relative tolerance.

    Returns
    -------
    bool
    """


def _undocumented_and_stale(freq, values, *, atol=0.0):
    """A parameter renamed without its docstring (``rtol`` -> ``atol``), another never written down.

    Parameters
    ----------
    freq : ndarray, shape (n_freq,)
        Frequencies [Hz].
    rtol : float
        Relative tolerance.
    """


def test_the_check_catches_missing_and_stale_parameters():
    assert documented_parameters(inspect.getdoc(_documented)) == ["freq", "values", "rtol"]
    assert parameter_problems(_documented) == []
    problems = parameter_problems(_undocumented_and_stale)
    assert problems == [
        "parameter 'values' is not documented",
        "parameter 'atol' is not documented",
        "documented parameter 'rtol' is not in the signature",
    ]
