"""The suite's scheduling list names real files: a renamed or removed slow file would otherwise silently fall
back to pytest's order (tests/conftest.py, LONGEST_FIRST)."""

from __future__ import annotations

from conftest import LONGEST_FIRST, ROOT


def test_every_longest_first_entry_is_a_test_file_once():
    missing = [p for p in LONGEST_FIRST if not (ROOT / p).is_file()]
    assert not missing, f"tests/conftest.py LONGEST_FIRST names files that do not exist: {missing}"
    assert len(set(LONGEST_FIRST)) == len(LONGEST_FIRST)
    assert all(p.startswith("tests/") and p.rsplit("/", 1)[1].startswith("test_") for p in LONGEST_FIRST)


def test_the_listed_files_are_collected_first(request):
    paths = [item.nodeid.split("::", 1)[0] for item in request.session.items]
    listed = [p for p in dict.fromkeys(paths) if p in LONGEST_FIRST]
    head = list(dict.fromkeys(paths))[:len(listed)]
    assert head == listed == [p for p in LONGEST_FIRST if p in listed]
