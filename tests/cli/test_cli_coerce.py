"""Plain option values converted without pydantic (jointdb.cli._coerce) give exactly what Typer's
own conversion gives, for every plain parameter of every command; other values go to Typer."""

import math
import subprocess
import sys
from pathlib import Path

import typer.main
from typer._click.exceptions import BadParameter
from typer._coercion import build_runtime_param

import jointdb.cli as cli
from jointdb.cli._coerce import _plain, install

SAMPLES = {
    str: ["", "abc", " x ", "ü-steel", "1e3", "a=b", "--x"],
    int: ["0", "7", "-3", "+5", "007", "123456789012345678", "1234567890123456789012", " 5", "5 ", "5.0", "1_000",
          "abc", "", "٣", 3, 0],
    float: ["35", "3.5", "-0.0", "1e3", "1E-3", ".5", "5.", "+2.5e+2", "1e400", "-1e400", "1e-400", "inf", "nan",
            " 2", "2 ", "1_0", "0x10", "abc", "", "٣", "0.1000000000000000055511151231257827", 3, 2.5, 2**60],
    bool: [True, False],
    Path: ["a.h5", ".", "", "no/such/dir/x.csv", "~/x", __file__],
}


def _same(a, b) -> bool:
    if type(a) is not type(b):
        return False
    if isinstance(a, float):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    if isinstance(a, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def _outcome(runtime, value, param):
    try:
        return "ok", runtime._coerce_value(value, param=param, ctx=None)
    except BadParameter as exc:
        return "bad", str(exc.message)


def _plain_params():
    command = typer.main.get_command(cli.app)
    install(command)
    stack, out = [command], []
    while stack:
        cmd = stack.pop()
        stack.extend(cmd.commands.values() if hasattr(cmd, "commands") else ())
        out.extend((cmd.name, p) for p in cmd.params if _plain(p.type_descriptor))
    return out


def test_every_plain_parameter_converts_like_typer():
    params = _plain_params()
    assert len(params) > 100  # most of the CLI's options are plain
    compared = 0
    for command, param in params:
        desc = param.type_descriptor
        leaf = desc.annotation.__args__[0] if getattr(desc.annotation, "__origin__", None) is list else desc.annotation
        many = leaf is not desc.annotation
        ours, typers = param._runtime_param, build_runtime_param(desc)
        assert type(ours).__name__ == "PlainRuntimeParam", (command, param.name)
        for value in SAMPLES[leaf]:
            value = (value, value) if many else value
            got, want = _outcome(ours, value, param), _outcome(typers, value, param)
            assert got[0] == want[0] and (_same(got[1], want[1]) if got[0] == "ok" else got[1] == want[1]), \
                (command, param.name, value, got, want)
            compared += 1
    assert compared > 500


def test_a_command_line_needs_no_pydantic_and_a_bad_value_keeps_typers_message(tmp_path):
    code = ("import sys\nsys.argv = ['jointdb', 'query', '--type', 'tool-holder', '--torque', '35', '-k', '2', "
            f"'--db', {str(tmp_path / 'none.sqlite')!r}]\n"
            "from jointdb.cli import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "print('PYDANTIC', 'pydantic' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert "PYDANTIC False" in out.stdout, out.stdout + out.stderr
    assert "does not exist" in out.stderr  # the query ran (no database there)
    bad = subprocess.run([sys.executable, "-m", "jointdb", "query", "--type", "tool-holder", "--torque", "abc"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "Invalid value for '--torque'" in bad.stderr, bad.stderr
