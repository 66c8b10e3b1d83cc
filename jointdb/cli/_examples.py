"""CLI: ``jointdb examples DIR`` copies the bundled example data out of the installed package."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointdb.cli._output import emit, message


def register(app: typer.Typer) -> None:
    """Add ``examples`` to the app."""

    @app.command("examples")
    def examples(
        out: Annotated[Path, typer.Argument(help="New (or empty) directory to copy the examples into.")],
        as_json: Annotated[bool, typer.Option("--json", help="Write JSON to stdout instead of a table.")] = False,
    ) -> None:
        """Copy the bundled example models, campaigns and stacks into a new directory.

        DIR/models (beam models), DIR/campaigns (the bundled tool-holder and holder-spindle test campaigns with their
        measured FRFs), DIR/stacks (a tool / holder / spindle stack). Works from any
        installation (the files are package data).
        Example: jointdb examples ex ; jointdb identify ex/campaigns/th-er32-steel-040nm/campaign.json --out joint.h5
        """
        from jointdb.usecases._examples import copy_examples

        files = copy_examples(out)
        message(f"copied {len(files)} example files to {out}")
        emit([{"file": (out / f).as_posix()} for f in files], as_json=as_json)
