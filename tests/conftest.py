"""Suite-wide settings: the tests never write into the user's own cache directory."""

from __future__ import annotations

import os
import tempfile

# The nearest-query cache (jointdb.store._qcache) goes to a directory of this test run, inherited by the
# `python -m jointdb` subprocesses the CLI tests start; a test that sets its own value still wins.
os.environ.setdefault("JOINTDB_QUERY_CACHE", tempfile.mkdtemp(prefix="jointdb-test-query-cache-"))
