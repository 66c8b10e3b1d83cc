"""CLI: ``jointdb demo`` — the main job end to end on the bundled data.

Part A (structural model): build a tool model from the model file bundled in
``jointdb/data/models/``, compute and print its modes, compute its tip FRF,
write it (UFF58 + CSV) and a Bode plot into ``OUT/tool-model/``. Each step is
one small function taking and returning a :class:`DemoState` (:data:`STEPS`).

Part B (the journey, :func:`jointdb.usecases._demo.run_main_job`): identify and
catalogue the bundled campaigns, query the nearest joint for a new stack,
predict its tool-tip FRF and draw its stability lobes, into ``OUT/``.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Optional

import numpy as np
import typer

from jointdb.errors import InputError

DEMO_MODEL = "end-mill-in-holder.json"


@dataclass
class DemoState:
    """What the demo's steps hand to each other."""

    out: Path
    model_path: Path | None = None
    model: Any = None
    modes: Any = None
    tip_frf: Any = None
    files: list[Path] = field(default_factory=list)
    fmax_hz: float = 8000.0
    df_hz: float = 2.0


def _say(text: str) -> None:
    from jointdb.cli._output import message

    message(text)


def bundled_model_text(name: str = DEMO_MODEL) -> str:
    """Text of a model file shipped in ``jointdb/data/models``."""
    ref = resources.files("jointdb").joinpath("data", "models", name)
    if not ref.is_file():
        raise InputError(f"bundled model {name!r} is missing from the installed package")
    return ref.read_text(encoding="utf-8")


def step_model(state: DemoState) -> DemoState:
    """1. Build the tool model (bundled stepped shaft, or --model)."""
    from jointdb.fe import load_model, model_from_dict

    if state.model_path is None:
        text = bundled_model_text()
        model = model_from_dict(json.loads(text))
        copy = state.out / DEMO_MODEL
        copy.write_text(text, encoding="utf-8")
        state.files.append(copy)
        source = f"bundled {DEMO_MODEL} (copied to {copy})"
    else:
        model = load_model(state.model_path)
        source = str(state.model_path)
    _say(f"[1] model: {model.name or source}")
    _say(
        f"    from {source}: {len(model.segments)} segments, length {model.length * 1e3:.1f} mm, "
        f"{model.theory}, {model.kind}, ingredients: "
        + (", ".join(type(i).__name__ for i in model.ingredients) or "none")
    )
    return dataclasses.replace(state, model=model)


def step_modes(state: DemoState) -> DemoState:
    """2. Natural frequencies (printed as a table) and modes.json."""
    from jointdb.cli._output import emit
    from jointdb.cli._models import mode_rows

    modes = state.model.modes(6)
    rows = mode_rows(modes)
    _say("[2] natural frequencies (undamped):")
    emit(rows, columns=["mode", "freq_hz", "type"], title="modes")
    path = state.out / "modes.json"
    path.write_text(json.dumps({"modes": rows}, indent=2) + "\n", encoding="utf-8")
    state.files.append(path)
    elastic = modes.freq_hz[modes.n_rigid:]
    fmax = state.fmax_hz
    if elastic.size >= 3:
        fmax = float(np.ceil(1.25 * elastic[2] / 1000.0) * 1000.0)
    return dataclasses.replace(state, modes=modes, fmax_hz=fmax)


def step_tip_frf(state: DemoState) -> DemoState:
    """3. Tip receptance by direct solution, checked against modal superposition."""
    model = state.model
    tip = "tip" if any(p.name == "tip" for p in model.points) else model.points[0].name
    n = int(round(state.fmax_hz / state.df_hz))
    freq = state.df_hz * np.arange(1, n + 1)
    frf = model.frf(freq, points=[tip], method="direct")
    modal = model.frf(freq, points=[tip], method="modal")
    h = frf.entry(frf.outputs[0], frf.inputs[0])
    hm = modal.entry(frf.outputs[0], frf.inputs[0])
    diff = float(np.max(np.abs(h - hm)) / np.max(np.abs(h)))
    k = int(np.argmax(np.abs(h)))
    _say(
        f"[3] tip FRF at point {tip!r}: {frf.n_freq} lines {freq[0]:g}-{freq[-1]:g} Hz, DOFs "
        + " ".join(map(str, frf.outputs))
    )
    _say(f"    largest |H[{frf.outputs[0]},{frf.inputs[0]}]| = {abs(h[k]):.3e} m/N at {freq[k]:g} Hz")
    _say(
        f"    direct vs modal superposition (modes < {2 * freq[-1]:g} Hz + static residual): "
        f"max difference {diff:.1e} of max |H[{frf.outputs[0]},{frf.inputs[0]}]|"
    )
    return dataclasses.replace(state, tip_frf=frf)


def step_write(state: DemoState) -> DemoState:
    """4. Write the tip FRF as UFF58 and CSV."""
    from jointdb.io import write_frf_csv, write_uff58

    uff = state.out / "tip-frf.uff"
    csv = state.out / "tip-frf.csv"
    write_uff58(uff, state.tip_frf)
    write_frf_csv(csv, state.tip_frf)
    state.files.extend([uff, csv])
    _say(f"[4] wrote {uff.name} (UFF58) and {csv.name}")
    return state


def step_plot(state: DemoState) -> DemoState:
    """5. Bode plot of the tip FRF."""
    from jointdb.plots._frf import save_bode

    png = state.out / "tip-frf-bode.png"
    save_bode(png, state.tip_frf, title=f"tip receptance — {state.model.name}")
    state.files.append(png)
    _say(f"[5] wrote {png.name}")
    return state


#: The demo's steps, in order.
STEPS: list[Callable[[DemoState], DemoState]] = [step_model, step_modes, step_tip_frf, step_write, step_plot]


def run_demo(out: Path, model_path: Path | None = None, db_url: str | None = None) -> tuple[DemoState, Any]:
    """Run part A (:data:`STEPS`) into ``out/tool-model`` and part B (the journey) into ``out``.

    Returns the structural-model state and the :class:`jointdb.usecases._demo.JourneyResult`.
    """
    from jointdb.usecases._demo import run_main_job

    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r} exists and is not a directory")
    model_dir = out / "tool-model"
    model_dir.mkdir(parents=True, exist_ok=True)
    _say("== Part A: structural model of a tool in its holder (Timoshenko beam FE)")
    state = DemoState(out=model_dir, model_path=model_path)
    for step in STEPS:
        state = step(state)
    _say("== Part B: catalogue joints -> query -> predict the tool tip -> stability lobes")
    journey = run_main_job(out, db_url, say=_say)
    return state, journey


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
        state, journey = run_demo(out, model, db)
        files = list(state.files) + list(journey.files)
        _say(f"demo complete: {len(files)} files (listed on stdout)")
        for f in files:
            typer.echo(str(f))
