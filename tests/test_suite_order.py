"""The suite's scheduling list names real files: a renamed or removed slow file would otherwise silently fall
back to pytest's order (tests/conftest.py, LONGEST_FIRST)."""

from __future__ import annotations

from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent


@pytest.fixture
def longest_first(request):
    """LONGEST_FIRST of tests/conftest.py, as pytest loaded it (other folders have conftest modules too)."""
    mine = TESTS / "conftest.py"
    for plugin in request.config.pluginmanager.get_plugins():
        if getattr(plugin, "__file__", None) and Path(plugin.__file__).resolve() == mine:
            return plugin.LONGEST_FIRST
    pytest.fail("tests/conftest.py is not loaded as a plugin")


def test_every_longest_first_entry_is_a_test_file_once(longest_first):
    missing = [p for p in longest_first if not (TESTS.parent / p).is_file()]
    assert not missing, f"tests/conftest.py LONGEST_FIRST names files that do not exist: {missing}"
    assert len(set(longest_first)) == len(longest_first)
    assert all(p.startswith("tests/") and p.rsplit("/", 1)[1].startswith("test_") for p in longest_first)


def test_the_listed_files_are_collected_first(request, longest_first):
    files = list(dict.fromkeys(item.nodeid.split("::", 1)[0] for item in request.session.items))
    listed = [p for p in files if p in longest_first]
    assert files[:len(listed)] == listed == [p for p in longest_first if p in listed]
