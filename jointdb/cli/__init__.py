"""The ``jointdb`` command line: a thin shell over the library.

Each command group lives in its own module (``_models``, ``_coupling``,
``_store``, ``_db``, ``_stability``, ``_predict``, ``_diagnose``, ``_demo``) and
registers itself on the one Typer app here; this keeps every file readable in
one sitting (design.md puts the CLI in one ``cli.py``; we split it along the
command groups for that reason). Output goes through :mod:`jointdb._output`.

User errors (:class:`jointdb.errors.JointdbError`) become one line on stderr
and the error class's exit code, with no traceback.
"""

from __future__ import annotations

import sys

import typer

from jointdb.errors import JointdbError

app = typer.Typer(
    name="jointdb",
    help="Identify, catalogue and reuse machine-tool joint dynamics.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _root() -> None:
    """jointdb: joint identification (IRC), a versioned joint database, tool-tip
    prediction (RC), chatter stability lobes and model/measurement diagnosis."""


def _register_all() -> None:
    from jointdb.cli import _coupling, _db, _demo, _diagnose, _models, _predict, _stability, _store

    for module in (_models, _coupling, _store, _db, _predict, _stability, _diagnose, _demo):
        module.register(app)


_register_all()


def main() -> None:
    """Console-script entry point: run the app, mapping jointdb errors to exit codes.

    Usage errors (unknown option, missing argument) are reported by Typer/Click
    itself with exit code 2; :class:`JointdbError` becomes one line on stderr
    and the error class's exit code.
    """
    try:
        app()
    except JointdbError as exc:
        sys.stderr.write(f"error: {exc}\n")
        sys.exit(exc.exit_code)
