"""The ``Examples`` of the public API run as doctests, and give what they show.

Collected from every module of :data:`docstring_helpers.PUBLIC_MODULES` and every module that
defines one of their public names (package docstrings, functions, classes and their methods).
Each module's examples run in one namespace, with numpy's print options fixed (8 significant
digits, no scientific-notation surprises) so the printed arrays are stable; ``...`` matches
anything (ELLIPSIS) and runs of whitespace compare equal. Any failing example fails the module.
"""

from __future__ import annotations

import doctest
import tempfile

import numpy as np
import pytest

from docstring_helpers import public_modules_with_docstrings

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _examples(module) -> list[doctest.DocTest]:
    finder = doctest.DocTestFinder(exclude_empty=True)
    return [t for t in finder.find(module, module.__name__) if t.examples]


MODULES = [m for m in sorted(public_modules_with_docstrings(), key=lambda m: m.__name__) if _examples(m)]


def _failures(tests: list[doctest.DocTest]) -> str:
    """Run ``tests`` with numpy's print options fixed; the runner's report of every failing example."""
    saved = np.get_printoptions()
    np.set_printoptions(precision=8, suppress=True, legacy=False)
    report = _Collector()
    try:
        runner = doctest.DocTestRunner(optionflags=FLAGS)
        for test in tests:
            runner.run(test, out=report)
    finally:
        np.set_printoptions(**saved)
    return report.text


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_examples_run(module, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # an example that writes a file writes it here,
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # and so does one that asks tempfile for a folder
    failures = _failures(_examples(module))
    assert not failures, failures


def test_a_wrong_example_fails():
    """The runner is not vacuous: an example whose shown output is wrong is reported, a right one is not."""
    def documented():
        """
        >>> import numpy as np
        >>> np.array([1.0, 2.0]) * 2
        array([2., 4.])
        >>> 1 + 1
        3
        """

    tests = doctest.DocTestFinder().find(documented, "documented", globs={})
    report = _failures(tests)
    assert "1 + 1" in report and "Expected:\n    3" in report
    assert "np.array" not in report


def test_there_are_examples():
    """The collection is not empty: at least the main entry points have examples (see test_docstrings)."""
    count = sum(len(t.examples) for m in MODULES for t in _examples(m))
    assert count >= 20, count


class _Collector:
    """The runner's report of a failure, kept for the assertion message."""

    def __init__(self):
        self.text = ""

    def __call__(self, text: str) -> None:
        self.text += text
