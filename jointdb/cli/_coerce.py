"""Command-line values of plain types converted without pydantic (start-up time).

Typer (0.2x and later) converts every parameter through a pydantic ``TypeAdapter``,
and importing pydantic and building the adapters costs a one-shot command like
``jointdb query`` about a third of its start-up. Most of our parameters are plain:
``str``, ``int``, ``float``, ``bool`` or ``Path`` (optional, or a repeated option of
them) without parser, bounds or path checks. :func:`install` gives those parameters of
a Click command built by Typer a conversion that returns what Typer's adapter returns
for the values a command line gives (a test compares them value by value); anything
else - another type, a constrained parameter, or a value this conversion does not
take (``--torque 1e400``, ``-k 1_000``, an empty path, ...) - goes to Typer's own
conversion, which then builds its adapter as before, with its own error message.

If Typer's internals are not the ones this module knows, :func:`install` does nothing.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, get_args, get_origin

_INT = re.compile(r"[+-]?[0-9]+")
#: decimal numbers only (no inf/nan, no underscores, no surrounding spaces, no hex)
_FLOAT = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_LEAVES = (str, int, float, bool, Path)


def _leaf(annotation) -> type | None:
    """The plain type of an annotation (``list[X]`` → ``X``), or None."""
    if get_origin(annotation) is list:
        args = get_args(annotation)
        annotation = args[0] if len(args) == 1 else None
    return annotation if annotation in _LEAVES else None


def _plain(descriptor) -> bool:
    info = descriptor.parameter_info
    return (descriptor.file_annotation is None and _leaf(descriptor.annotation) is not None
            and getattr(info, "parser", None) is None and getattr(info, "click_type", None) is None
            and getattr(info, "min", None) is None and getattr(info, "max", None) is None
            and not getattr(info, "clamp", False) and getattr(info, "path_type", None) is None
            and not getattr(info, "resolve_path", False) and not getattr(info, "allow_dash", False)
            and not getattr(info, "exists", False))


_MISS = object()


def convert(kind: type, value: Any) -> Any:
    """``value`` as ``kind`` the way Typer's adapter converts it, or :data:`_MISS` when this
    function does not take the value (the caller then asks Typer)."""
    if kind is str:
        return value if isinstance(value, str) else _MISS
    if kind is bool:
        return value if isinstance(value, bool) else _MISS
    if kind is int:
        if type(value) is int:
            return value
        if isinstance(value, str) and len(value) <= 18 and _INT.fullmatch(value):
            return int(value)
        return _MISS
    if kind is float:
        if type(value) is float:
            return value
        if type(value) is int and abs(value) < 2**53:
            return float(value)
        if isinstance(value, str) and len(value) <= 40 and _FLOAT.fullmatch(value):
            x = float(value)
            return x if x not in (float("inf"), float("-inf")) else _MISS
        return _MISS
    if kind is Path:
        if isinstance(value, Path):
            return value
        if isinstance(value, str) and value and "\0" not in value:
            return Path(value)
        return _MISS
    return _MISS


def _runtime_param_class():
    from typer._coercion import RuntimeParam, build_runtime_param
    from typer._param_types import coerce_cli_path

    class PlainRuntimeParam(RuntimeParam):
        """Conversion of a plain parameter (module docstring); Typer's own for the rest."""

        def _coerce_value(self, value, param, ctx):
            kind = _leaf(self.annotation)
            many = get_origin(self.annotation) is list
            items = (value if isinstance(value, (list, tuple)) else [value]) if many else [value]
            out = [convert(kind, v) for v in items]
            if any(v is _MISS for v in out):  # Typer's conversion (and its message for a bad value)
                return build_runtime_param(param.type_descriptor)._coerce_value(value, param=param, ctx=ctx)
            if kind is Path:  # what Typer checks of a path once it is one (exists, readable, ...)
                out = [coerce_cli_path(v, self.parameter_info, path_type=Path, param=param, ctx=ctx) for v in out]
            return out if many else out[0]

    return PlainRuntimeParam


def install(command) -> None:
    """Give the plain parameters of ``command`` (a Click command or group built by Typer,
    and its subcommands; their help options when Click makes them) the conversion of
    this module."""
    try:
        cls = _runtime_param_class()
    except ImportError:  # another Typer: its own conversion everywhere
        return

    def give(param) -> None:
        desc = getattr(param, "type_descriptor", None)
        if desc is not None and getattr(param, "_runtime_param", _MISS) is None and _plain(desc):
            param._runtime_param = cls(parameter_info=desc.parameter_info, annotation=desc.annotation)

    def with_help(get_help_option):
        def wrapped(ctx):
            option = get_help_option(ctx)
            if option is not None:
                give(option)
            return option
        return wrapped

    stack = [command]
    while stack:
        cmd = stack.pop()
        stack.extend(getattr(cmd, "commands", {}).values())
        for param in getattr(cmd, "params", ()):
            give(param)
        if hasattr(cmd, "get_help_option"):  # made on first use (it depends on the context)
            cmd.get_help_option = with_help(cmd.get_help_option)
