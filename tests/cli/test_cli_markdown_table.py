"""Piped tables written without Rich (jointdb.cli._mdtable) are exactly what Rich writes, and Rich
still writes every table this module does not take."""

import io
import sys

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import jointdb.cli._output as output
from jointdb.cli._mdtable import _NARROW, render


def _emit(monkeypatch, data, rich: bool, **kw) -> str:
    buf = io.StringIO()  # not a terminal: the Markdown table
    monkeypatch.setattr(sys, "stdout", buf)
    if rich:
        monkeypatch.setattr(output, "_markdown_table", lambda *a: None)
    try:
        output.emit(data, **kw)
    finally:
        monkeypatch.undo()
    return buf.getvalue()


def test_the_characters_taken_as_one_cell_are_one_cell_for_rich():
    from rich.cells import cell_len

    taken = [chr(i) for i in range(0x300) if chr(i).isprintable()] + sorted(_NARROW)
    assert all(cell_len(ch) == 1 for ch in taken), [ch for ch in taken if cell_len(ch) != 1]


TEXT = st.text(alphabet=st.sampled_from("abcXYZ019 -_.,()=+*/#|\\[]:;'\"~äöüßé·°µ±×–—…€漢\u0301\n\t"), max_size=12)
VALUE = st.one_of(st.none(), TEXT, st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
                  st.booleans(), st.lists(st.floats(-1e3, 1e3), min_size=2, max_size=3))
KEYS = st.lists(st.sampled_from(["name", "version", "torque_nm", "preload_n", "depth_mm", "d_x", "k [N/m]", "a|b",
                                 "peak (Hz)", "spindle_speed_rpm", "materials", "z"]), min_size=1, max_size=5,
                unique=True)


@settings(max_examples=300, deadline=None)
@given(keys=KEYS, data=st.data(), title=st.one_of(st.none(), TEXT))
def test_rows_are_written_as_rich_writes_them(keys, data, title):
    rows = [{k: data.draw(VALUE) for k in keys} for _ in range(data.draw(st.integers(0, 4)))]
    with pytest.MonkeyPatch.context() as mp:
        want = _emit(mp, rows, rich=True, title=title)
    with pytest.MonkeyPatch.context() as mp:
        got = _emit(mp, iter(rows), rich=False, title=title)  # any iterable of rows
    assert got == want


@settings(max_examples=200, deadline=None)
@given(record=st.dictionaries(TEXT, VALUE, max_size=5), title=st.one_of(st.none(), TEXT))
@example(record={}, title="[/]")  # a title is text, never rich markup (Rich raised MarkupError on these)
@example(record={"a": 1}, title="[/0] [bold]x :smile:")
def test_a_record_is_written_as_rich_writes_it(record, title):
    with pytest.MonkeyPatch.context() as mp:
        want = _emit(mp, record, rich=True, title=title)
    with pytest.MonkeyPatch.context() as mp:
        got = _emit(mp, record, rich=False, title=title)
    assert got == want


def test_the_query_table_is_taken_and_odd_ones_are_left_to_rich(monkeypatch):
    rows = [{"name": "th-1", "version": 1, "distance": 0.12, "torque_nm": 40.0, "materials": "steel+steel"}]
    assert render("nearest tool-holder joints (distance = sqrt(sum d_i^2))", ["name", "torque [N·m]"],
                  [["th-1", "40"]]) is not None
    assert render(None, ["a"], [["漢字"]]) is None and render(None, ["a"], [["x\ny"]]) is None
    assert render("[bold]t", ["a"], [["x"]]) is None and render("t :smile:", ["a"], [["x"]]) is None
    monkeypatch.setenv("FORCE_COLOR", "1")
    assert render(None, ["a"], [["x"]]) is None
    monkeypatch.delenv("FORCE_COLOR")
    assert _emit(monkeypatch, rows, rich=False, title="t") == _emit(monkeypatch, rows, rich=True, title="t")
