"""What a failed job shows its owner: a user's error keeps its message; a server-side failure does not
show its text (it may name server folders), which goes to the worker's log."""

import logging

from jointdb.errors import InputError, IntegrityError, JointdbError
from jointdb.jobs._execute import _shown_error


def test_a_users_error_keeps_its_message():
    assert _shown_error("j1", InputError("spec.holders[0]: no such part")) == "spec.holders[0]: no such part"


def test_damaged_data_says_what_failed():
    assert "checksum" in _shown_error("j1", IntegrityError("blob abc: checksum mismatch"))


def test_a_server_side_failure_is_internal_and_logged(caplog):
    exc = JointdbError("cannot write to the blob store /srv/jointdb/blobs (disk full)")
    with caplog.at_level(logging.ERROR, logger="jointdb.jobs"):
        shown = _shown_error("j1", exc)
    assert "/srv" not in shown and shown.startswith("internal error (JointdbError)")
    assert "/srv/jointdb/blobs" in caplog.text


def test_a_bug_is_internal_and_logged_with_its_traceback(caplog):
    try:
        {}["/srv/secret"]
    except KeyError as exc:  # raised, so that it carries a traceback
        bug = exc
    with caplog.at_level(logging.ERROR, logger="jointdb.jobs"):
        shown = _shown_error("j1", bug)
    assert shown == "internal error (KeyError); the worker's log has the details"
    assert "/srv/secret" in caplog.text and "Traceback" in caplog.text
