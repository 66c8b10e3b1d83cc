"""CLI start-up: ``jointdb --help`` lists the commands without importing them, ``jointdb <command>``
imports only the module of that command, and both behave exactly like the app with every command."""

import importlib
import subprocess
import sys

import typer
import typer.main
from typer.testing import CliRunner

import jointdb.cli as cli


def _modules_after(args):
    code = (
        "import sys\n"
        f"sys.argv = ['jointdb'] + {args!r}\n"
        "from jointdb.cli import main\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "print('MODULES', ' '.join(sorted(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    line = next(x for x in out.stdout.splitlines() if x.startswith("MODULES "))
    return set(line.split()[1:])


def test_command_table_matches_the_registered_commands():
    full = typer.main.get_command(cli.app)
    assert list(full.commands) == list(cli.COMMANDS)
    for name, command in full.commands.items():
        module, summary = cli.COMMANDS[name]
        assert (command.help or "").split("\n\n")[0] == summary, name
    for module in cli.MODULES:  # each module registers exactly the commands the table gives it
        app = typer.Typer()

        @app.callback()
        def _root() -> None:
            pass

        importlib.import_module(f"jointdb.cli.{module}").register(app)
        got = set(typer.main.get_command(app).commands)
        assert got == {n for n, (m, _) in cli.COMMANDS.items() if m == module}, module


def test_root_help_is_the_same_as_with_every_command_registered():
    runner = CliRunner()
    for args in (["--help"], []):
        want = runner.invoke(cli.app, args, prog_name="jointdb")
        got = runner.invoke(cli._summary_app(), args, prog_name="jointdb")
        assert got.output == want.output and got.exit_code == want.exit_code


def test_a_command_runs_from_its_own_module_alone(tmp_path):
    runner = CliRunner()
    for args in (["modes", "--help"], ["query", "--help"], ["joints", "list", "--help"], ["lobes", "--nope"]):
        module = cli.COMMANDS[args[0]][0]
        want = runner.invoke(cli.app, args, prog_name="jointdb")
        got = runner.invoke(cli._app_with({module}), args, prog_name="jointdb")
        assert got.output == want.output and got.exit_code == want.exit_code, args


def test_help_imports_no_command_module_nor_numerics():
    loaded = _modules_after(["--help"])
    heavy = {"numpy", "scipy", "rich", "sqlalchemy", "alembic", "h5py", "pyuff", "matplotlib"}
    assert not loaded & heavy, loaded & heavy
    # the thread policy (jointdb.cli._threads, stdlib only) must run before numpy loads, so it is
    # the one private module every start imports; no command module is
    assert not {m for m in loaded if m.startswith("jointdb.cli._") and m != "jointdb.cli._threads"}
    loaded = _modules_after(["modes", "--help"])
    assert "jointdb.cli._models" in loaded
    assert not {"sqlalchemy", "jointdb.cli._store", "jointdb.cli._diagnose", "matplotlib"} & loaded
