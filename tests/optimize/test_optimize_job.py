"""The optimize job's runner (jointdb.jobs): field-checked options, progress through the search, and a cancel
that stops it at the next chunk of candidates."""

import json
from pathlib import Path

import pytest

from jointdb.errors import InputError
from jointdb.jobs._run import Cancelled, Progress, run

SPEC = json.loads((Path(__file__).resolve().parents[2] / "fixtures" / "optimize" / "optimize-catalogue.json").read_text())


def test_a_cancel_stops_the_optimize_job_at_its_next_step(catalogue):
    repo, _ = catalogue
    seen = []

    def record(fraction, message):
        seen.append((fraction, message))
        return fraction > 0.05  # a cancel asked for once the search has started

    with pytest.raises(Cancelled):
        run("optimize", {"spec": SPEC, "simulate": False}, None, repo, Progress(record))
    # stopped at the first report after the spec was read: the end of the search (36 candidates are one
    # chunk), before any semi-discretization check
    assert [m for _, m in seen] == ["reading the spec and the parts", "36/36 candidates (in-process)"]


def test_the_job_reports_progress_to_the_end(catalogue):
    repo, _ = catalogue
    seen = []
    result, artifact = run("optimize", {"spec": SPEC, "simulate": False, "top": 3}, None, repo,
                           Progress(lambda f, m: seen.append((f, m)) or False))
    assert artifact is None and len(result["ranked"]) == 3 and result["candidates"] == 36
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 0.95
    assert any("confirmed by semi-discretization" in m for _, m in seen)


@pytest.mark.parametrize("payload, needle", [
    ({"top": True}, "top: a whole number"), ({"top": 10_000}, "top: a whole number"),
    ({"simulate": "yes"}, "simulate: true or false"), ({"spec": "x.json"}, "spec: an optimize spec is a JSON object"),
])
def test_bad_options_are_named(catalogue, payload, needle):
    repo, _ = catalogue
    with pytest.raises(InputError, match=needle):
        run("optimize", {"spec": SPEC, **payload}, None, repo, Progress(lambda f, m: False))
