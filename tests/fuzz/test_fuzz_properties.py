"""Property-based fuzzing (hypothesis): random byte mutations and truncations of valid FRF files,
and random values in a valid model description, never give anything but jointdb's own errors.

The readers are called directly (the CLI adds only the error-to-exit-code
mapping, exercised by the corpus files); any other exception is a traceback a
user would see.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np
from fuzz_helpers import model_doc, seed_bytes
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointdb.errors import JointdbError

SETTINGS = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True, database=None)


@st.composite
def mutated(draw, seed: bytes):
    """``seed`` with 1–8 bytes replaced (often by digits, signs or line breaks) and maybe truncated."""
    data = bytearray(seed)
    for _ in range(draw(st.integers(1, 8))):
        pos = draw(st.integers(0, len(data) - 1))
        data[pos] = draw(st.one_of(st.integers(0, 255), st.sampled_from(list(b"0123456789-+.eEnNaI \n"))))
    if draw(st.booleans()):
        data = data[: draw(st.integers(0, len(data)))]
    return bytes(data)


def _read_all(path: Path, kind: str) -> None:
    from jointdb import io

    try:
        if kind == "uff":
            frf = io.read_frf_uff58(path)
            io.read_coherence_uff58(path, frf)
        elif kind == "h5":
            io.read_frf_hdf5_full(path)
        else:
            io.read_frf_csv(path)
    except JointdbError as exc:
        assert "\n" not in str(exc), str(exc)


def _check(data: bytes, suffix: str, kind: str) -> None:
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / f"f{suffix}"
        p.write_bytes(data)
        _read_all(p, kind)


@settings(SETTINGS, max_examples=150)
@given(mutated(seed_bytes("uff")))
def test_mutated_ascii_uff58_never_gives_a_traceback(data):
    _check(data, ".uff", "uff")


@settings(SETTINGS, max_examples=80)
@given(mutated(seed_bytes("uffb")))
def test_mutated_binary_uff58_never_gives_a_traceback(data):
    _check(data, ".uff", "uff")


@settings(SETTINGS, max_examples=60)
@given(mutated(seed_bytes("h5")))
def test_mutated_hdf5_never_gives_a_traceback(data):
    _check(data, ".h5", "h5")


@settings(SETTINGS, max_examples=80)
@given(mutated(seed_bytes("csv")))
def test_mutated_csv_never_gives_a_traceback(data):
    _check(data, ".csv", "csv")


_JSON_VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-(10**40), 10**40),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5),
    st.lists(st.floats(-1e3, 1e3), max_size=3), st.dictionaries(st.sampled_from(["x", "y", "ry"]), st.floats(), max_size=2),
)


def _paths(doc, prefix=()):
    """Every (path) to a leaf or container in a JSON document."""
    yield prefix
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, prefix + (i,))


MODEL_PATHS = [p for p in _paths(model_doc()) if p]


@settings(SETTINGS, max_examples=200)
@given(st.lists(st.tuples(st.sampled_from(MODEL_PATHS), _JSON_VALUES), min_size=1, max_size=3))
def test_model_with_random_values_is_built_or_refused_in_one_line(changes):
    from jointdb.fe import model_from_dict

    doc = model_doc()
    for path, value in changes:
        target = doc
        try:
            for k in path[:-1]:
                target = target[k]
            target[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue  # an earlier change replaced the container
    # through JSON text as a file would be (NaN/Infinity survive, as Python's json writes them)
    doc = json.loads(json.dumps(doc))
    try:
        model = model_from_dict(doc)
    except JointdbError as exc:
        assert "\n" not in str(exc), str(exc)
        return
    n_dof = len(model.mesh().dof_labels())
    assert n_dof <= 6 * 1001 and np.isfinite(model.length)
