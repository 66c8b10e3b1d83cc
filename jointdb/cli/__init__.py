"""The ``jointdb`` command line: a thin shell over the library.

Each command group lives in its own module (``_models``, ``_coupling``,
``_store``, ``_db``, ``_stability``, ``_predict``, ``_diagnose``, ``_demo``) and
registers itself on a Typer app; this keeps every file readable in one sitting
(one module per command group rather than one ``cli.py``, for that reason). Output goes through :mod:`jointdb._output`.

User errors (:class:`jointdb.errors.JointdbError`) become one line on stderr
and the error class's exit code, with no traceback.

Start-up: ``jointdb <command>`` imports only the module that registers that
command, and ``jointdb --help`` none (it lists :data:`COMMANDS`, whose
summaries a test keeps equal to the commands' own help). Help and usage errors
are formatted by Click without Rich: Typer's Rich help imports a Markdown
renderer that costs as much as numpy. :data:`app` — every command registered —
is built on first use, for running the CLI in-process (tests, other programs).
"""

from __future__ import annotations

import sys

import typer

from jointdb.errors import JointdbError

#: The command modules, in the order they register (which is the order of ``jointdb --help``).
MODULES = ("_models", "_coupling", "_store", "_parts", "_db", "_predict", "_stability", "_diagnose", "_demo",
           "_examples", "_campaign", "_plan", "_serve", "_worker")

#: Commands that use the database itself and have no HTTP counterpart: an explicit ``--server`` is refused
#: (``joints export|import`` refuse it themselves; catalogue, query, joints ..., predict use the server).
LOCAL_ONLY = ("db", "tokens", "serve", "worker", "demo")

#: Every top-level command as ``jointdb --help`` lists it: the module that registers it and
#: the first paragraph of its help.
COMMANDS: dict[str, tuple[str, str]] = {
    "modes": ("_models", "Natural frequencies of a beam model (undamped), lowest first."),
    "frf": ("_models", "FRFs between named points of a beam model, to UFF58 / HDF5 / CSV and a Bode plot."),
    "identify": (
        "_coupling",
        "Identify a joint (IRC) from a campaign's measured assembly FRFs and substructure models.",
    ),
    "couple": (
        "_coupling",
        "Couple a campaign's substructures through a joint (RC) and compare with its measurements.",
    ),
    "catalogue": ("_store", "Catalogue an identified joint FRF as a new immutable version."),
    "query": ("_store", "Find the k catalogued joints closest to given conditions (distance per condition)."),
    "predict": ("_predict", "Predict the tool-tip FRF of a tool / holder / spindle stack (three-component RC)."),
    "modal-fit": ("_stability", "Fit modes to an FRF (pLSCF poles + LSFD residues) and report the fit quality."),
    "lobes": ("_stability", "Stability lobes from a tool-tip FRF (turning: Tlusty; milling: ZOA or SD)."),
    "diagnose": ("_diagnose", "Locate where a model and recordings disagree, name the missing physics, refit."),
    "diagnose-bench": ("_diagnose", "Run the concealed-effect benchmark: generate, diagnose, score per effect."),
    "demo": ("_demo", "Run the main job end to end on the bundled data (SQLite, bundled fixtures)."),
    "examples": ("_examples", "Copy the bundled example models, campaigns and stacks into a new directory."),
    "rotations": (
        "_campaign",
        "Rotational receptances at a contact point from translational measurements, with noise amplification.",
    ),
    "plan": ("_plan", "Rank candidate tap points by the expected joint-parameter variance (Fisher information)."),
    "serve": ("_serve", "Run the HTTP API and web catalogue (FastAPI + uvicorn) over the joint database."),
    "worker": ("_worker", "Run jobs of the HTTP service (predict, lobes, diagnose, identify) from the PostgreSQL queue."),
    "joints": ("_store", "List, inspect, label, deprecate, diff, export and import catalogued joints."),
    "keys": ("_store", "Ed25519 keys to sign exported bundles and verify imported ones."),
    "parts": ("_parts", "Catalogued stack parts (spindles, holders, tools): add, list, show, label."),
    "db": ("_db", "Database administration: migrations, integrity check, garbage collection."),
    "campaign": ("_campaign", "Scaffold a measurement campaign from a folder of files, or check one."),
    "tokens": ("_serve", "API tokens of the HTTP service: create, list, revoke."),
}


def _new_app() -> typer.Typer:
    app_ = typer.Typer(
        name="jointdb",
        help="Identify, catalogue and reuse machine-tool joint dynamics.",
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        rich_markup_mode=None,  # plain Click help: no Rich/Markdown import at start-up
    )

    def _show_version(value: bool) -> None:
        if value:
            from jointdb import __version__

            typer.echo(f"jointdb {__version__}")
            raise typer.Exit()

    @app_.callback()
    def _root(
        ctx: typer.Context,
        verbose: int = typer.Option(0, "-v", "--verbose", count=True, show_default=False,
                                    help="More log messages on stderr (-v: info, -vv: debug)."),
        quiet: bool = typer.Option(False, "-q", "--quiet", help="Only warnings and errors on stderr; no progress."),
        version: bool = typer.Option(False, "--version", is_eager=True, callback=_show_version,
                                     help="Print the jointdb version and exit."),
        server: str = typer.Option(None, "--server", metavar="URL",
                                   help="Use a jointdb server instead of a database (or $JOINTDB_SERVER; "
                                        "token from $JOINTDB_TOKEN)."),
        blas_threads: int = typer.Option(None, "--blas-threads", metavar="N",  # checked in main()
                                         help="BLAS/OpenMP threads for the linear algebra (default 1, or "
                                              "$JOINTDB_BLAS_THREADS; 0: the library default). Set before "
                                              "numpy loads; inherited by the service's workers."),
    ) -> None:
        """jointdb: joint identification (IRC), a versioned joint database, tool-tip
        prediction (RC), chatter stability lobes and model/measurement diagnosis."""
        from jointdb._output import configure_logging

        configure_logging(verbose, quiet)
        if server:
            import os

            os.environ["JOINTDB_SERVER"] = server
            command = ctx.invoked_subcommand
            if command in LOCAL_ONLY:
                from jointdb.errors import InputError

                raise InputError(f"`jointdb {command}` does not work over --server: it needs the database itself "
                                 "(give --db URL, or run it where the database is)")

    return app_


def _app_with(modules, only: str | None = None) -> typer.Typer:
    """An app with the commands of the given modules registered (``only``: just that command,
    so that Typer builds one Click command, not every command of its module)."""
    import importlib

    app_ = _new_app()
    for name in MODULES:
        if name in modules:
            importlib.import_module(f"jointdb.cli.{name}").register(app_)
    if only is not None:
        app_.registered_commands = [c for c in app_.registered_commands if c.name == only]
        app_.registered_groups = [g for g in app_.registered_groups if g.name == only]
    return app_


def _summary_app() -> typer.Typer:
    """The root app for ``jointdb`` / ``jointdb --help``: each command a stub with its summary."""
    app_ = _new_app()
    for name, (_, summary) in COMMANDS.items():

        def stub() -> None:
            pass

        stub.__doc__ = summary
        app_.command(name)(stub)
    return app_


_full_app: typer.Typer | None = None


def __getattr__(name: str):
    if name == "app":  # every command registered, built once
        global _full_app
        if _full_app is None:
            _full_app = _app_with(MODULES)
        return _full_app
    raise AttributeError(f"module 'jointdb.cli' has no attribute {name!r}")


def _click_errors():
    """Click's usage-error, error and abort classes (Typer vendors Click in recent releases;
    a separately installed Click, e.g. uvicorn's, is then not the one Typer raises)."""
    try:
        from typer import Abort
        from typer._click.exceptions import ClickException, UsageError
    except ImportError:
        from click import Abort, ClickException, UsageError
    return UsageError, ClickException, Abort


def main() -> None:
    """Console-script entry point: run the app, mapping jointdb errors to exit codes.

    Usage errors (unknown option, missing argument, a value of the wrong type)
    become one ``error:`` line on stderr with exit code 2; :class:`JointdbError`
    becomes one line on stderr and the error class's exit code.
    """
    args = sys.argv[1:]
    from jointdb.cli._threads import apply_thread_policy, requested_threads

    try:  # before anything imports numpy: the thread variables are read when BLAS loads
        apply_thread_policy(*requested_threads(args))
    except ValueError as exc:
        sys.stderr.write(f"error: {exc}\n")
        sys.exit(2)
    # -v/-q may be written after the command too (`jointdb lobes ... -q`): they are the app's, moved to the front
    upto = args.index("--") if "--" in args else len(args)
    is_global = [a in ("-q", "--quiet", "--verbose") or (a[:2] == "-v" and set(a[1:]) == {"v"}) for a in args[:upto]]
    args = [a for a, g in zip(args, is_global) if g] + [a for a, g in zip(args, is_global) if not g] + args[upto:]
    # the first word that is not a root option (-v/-vv/-q/--verbose/--quiet, --server URL) names the command
    first, i = None, 0
    while i < len(args):
        a = args[i]
        if a in ("--server", "--blas-threads"):
            i += 2
        elif a.startswith(("--server=", "--blas-threads=")) or a in ("--verbose", "--quiet") or (
                a[:1] == "-" and a[1:2] != "-" and set(a[1:]) <= {"v", "q"}):
            i += 1
        else:
            first = a
            break
    if first in COMMANDS:
        cli = _app_with({COMMANDS[first][0]}, only=first)
    elif first is None or first in ("--help", "--version"):
        cli = _summary_app()
    else:  # anything else (an unknown command, ...): the full app, for Click's own messages
        cli = __getattr__("app")
    UsageError, ClickException, Abort = _click_errors()
    command = typer.main.get_command(cli)
    if first in COMMANDS:  # plain option values converted without importing pydantic (start-up time)
        from jointdb.cli._coerce import install

        install(command)
    try:
        rv = command.main(args=args, prog_name="jointdb", standalone_mode=False)
    except JointdbError as exc:
        sys.stderr.write(f"error: {exc}\n")
        sys.exit(exc.exit_code)
    except UsageError as exc:
        # one line, like every other error: what is wrong and where to look
        where = exc.ctx.command_path if exc.ctx is not None else "jointdb"
        text = " ".join(exc.format_message().split())
        sys.stderr.write(f"error: {text} (see '{where} --help')\n")
        sys.exit(exc.exit_code)
    except ClickException as exc:
        sys.stderr.write(f"error: {exc.format_message()}\n")
        sys.exit(exc.exit_code)
    except Abort:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)
    if isinstance(rv, int) and rv:
        sys.exit(rv)
