"""CLI: ``jointdb demo`` — the main job end to end on the bundled data (thin: the steps are the
use case :func:`jointdb.usecases.run_demo`; here they are only rendered).

Part A (structural model): build a tool model from the model file bundled in
``jointdb/data/models/``, compute and print its modes, compute its tip FRF, write it
(UFF58 + CSV) and a Bode plot into ``OUT/tool-model/``. Part B (the journey,
:func:`jointdb.usecases._demo.run_main_job`): identify and catalogue the bundled campaigns,
query the nearest joint for a new stack, predict its tool-tip FRF and draw its stability
lobes, into ``OUT/``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer


def register(app: typer.Typer) -> None:
    """Add ``demo`` to the app."""

    @app.command("demo")
    def demo_cmd(
        out: Annotated[Path, typer.Option("--out", help="Directory for the outputs (created if needed).")] = Path(
            "jointdb-demo-output"
        ),
        model: Annotated[
            Optional[Path], typer.Option("--model", help="Use this model file for part A instead of the bundled one.")
        ] = None,
        db: Annotated[
            Optional[str],
            typer.Option("--db", help="Joint database URL or SQLite path (default: a fresh OUT/joints.sqlite)."),
        ] = None,
    ) -> None:
        """Run the main job end to end on the bundled data (SQLite, bundled fixtures).

        Part A: tool model, modes, tip FRF, files, Bode plot. Part B: identify and
        catalogue six tool-holder and six holder-spindle joints, query the nearest
        for both interfaces of a new stack (two bending planes), predict
        its tool-tip FRF and draw milling stability lobes. Lists the files written.

        Example: jointdb demo --out demo-out
        """
        from jointdb.cli._output import emit, message
        from jointdb.usecases import run_demo

        state, journey = run_demo(out, model, db, say=message,
                                  table=lambda rows, columns, title: emit(rows, columns=columns, title=title))
        files = list(state.files) + list(journey.files)
        message(f"demo complete: {len(files)} files (listed on stdout)")
        for f in files:
            typer.echo(str(f))
