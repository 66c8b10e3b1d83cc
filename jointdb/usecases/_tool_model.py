"""The demo's part A as a use case: a tool model from a model file, its modes, its tip FRF
(direct, checked against modal superposition), written as UFF58 and CSV with a Bode plot —
then part B, the main job (:func:`jointdb.usecases._demo.run_main_job`).

Each step is one small function taking and returning a :class:`DemoState` (:data:`STEPS`);
what a person should see goes through the state's ``say`` (a line) and ``table`` (rows),
which the shell renders.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import InputError

__all__ = ["DemoState", "STEPS", "run_demo", "mode_rows", "bundled_model_text", "DEMO_MODEL"]

DEMO_MODEL = "end-mill-in-holder.json"


@dataclass
class DemoState:
    """What the demo's steps hand to each other."""

    out: Path
    say: Callable[[str], None]
    table: Callable[[list[dict], list[str], str], None]
    model_path: Path | None = None
    model: Any = None
    modes: Any = None
    tip_frf: Any = None
    files: list[Path] = field(default_factory=list)
    fmax_hz: float = 8000.0
    df_hz: float = 2.0


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
    state.say(f"[1] model: {model.name or source}")
    state.say(
        f"    from {source}: {len(model.segments)} segments, length {model.length * 1e3:.1f} mm, "
        f"{model.theory}, {model.kind}, ingredients: "
        + (", ".join(type(i).__name__ for i in model.ingredients) or "none")
    )
    return dataclasses.replace(state, model=model)


def step_modes(state: DemoState) -> DemoState:
    """2. Natural frequencies (printed as a table) and modes.json."""
    modes = state.model.modes(6)
    rows = mode_rows(modes)
    state.say("[2] natural frequencies (undamped):")
    state.table(rows, ["mode", "freq_hz", "type"], "modes")
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
    state.say(
        f"[3] tip FRF at point {tip!r}: {frf.n_freq} lines {freq[0]:g}-{freq[-1]:g} Hz, DOFs "
        + " ".join(map(str, frf.outputs))
    )
    state.say(f"    largest |H[{frf.outputs[0]},{frf.inputs[0]}]| = {abs(h[k]):.3e} m/N at {freq[k]:g} Hz")
    state.say(
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
    state.say(f"[4] wrote {uff.name} (UFF58) and {csv.name}")
    return state


def step_plot(state: DemoState) -> DemoState:
    """5. Bode plot of the tip FRF."""
    from jointdb.plots._frf import save_bode

    png = state.out / "tip-frf-bode.png"
    save_bode(png, state.tip_frf, title=f"tip receptance — {state.model.name}")
    state.files.append(png)
    state.say(f"[5] wrote {png.name}")
    return state


#: The demo's steps, in order.
STEPS: list[Callable[[DemoState], DemoState]] = [step_model, step_modes, step_tip_frf, step_write, step_plot]


def run_demo(out: Path, model_path: Path | None = None, db_url: str | None = None, *,
             say: Callable[[str], None] = lambda text: None,
             table: Callable[[list[dict], list[str], str], None] = lambda rows, columns, title: None,
             ) -> tuple[DemoState, Any]:
    """Run part A (:data:`STEPS`) into ``out/tool-model`` and part B (the journey) into ``out``.

    Parameters
    ----------
    out : Path
        Directory of the outputs (created if needed).
    model_path : Path, optional
        A model file for part A instead of the bundled one.
    db_url : str, optional
        Joint database URL or SQLite path (default: a fresh ``out/joints.sqlite``).
    say : callable
        Called with each line of progress for people.
    table : callable
        Called with ``(rows, columns, title)`` of each table to show (the modes).

    Returns
    -------
    tuple
        The structural-model state (:class:`DemoState`, its ``files``) and the
        :class:`jointdb.usecases._demo.JourneyResult` (its ``files``).
    """
    from jointdb.usecases._demo import run_main_job

    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r} exists and is not a directory")
    model_dir = out / "tool-model"
    model_dir.mkdir(parents=True, exist_ok=True)
    say("== Part A: structural model of a tool in its holder (Timoshenko beam FE)")
    state = DemoState(out=model_dir, say=say, table=table, model_path=model_path)
    for step in STEPS:
        state = step(state)
    say("== Part B: catalogue joints -> query -> predict the tool tip -> stability lobes")
    journey = run_main_job(out, db_url, say=say)
    return state, journey


def mode_rows(modes) -> list[dict]:
    """One row per mode: number, frequency [Hz], and its dominant motion.

    Parameters
    ----------
    modes
        Normal modes of a beam model (:func:`jointdb.fe.normal_modes`).

    Returns
    -------
    list of dict
        ``mode`` (from 1), ``freq_hz`` and ``type``, the dominant motion (bending plane, axial or torsion).
    """
    labels = modes.dof_labels
    dirs = np.array([d.direction for d in labels])
    families = {
        "bending x-z": np.isin(dirs, ["x", "ry"]),
        "bending y-z": np.isin(dirs, ["y", "rx"]),
        "axial": dirs == "z",
        "torsion": dirs == "rz",
    }
    planar = not families["axial"].any()
    rows = []
    for k, f in enumerate(modes.freq_hz):
        shape = modes.shapes[:, k]
        if k < modes.n_rigid:
            kind = "rigid body"
        elif planar:
            kind = "bending"
        else:
            share = {name: float(np.sum(shape[mask] ** 2)) for name, mask in families.items()}
            total = sum(share.values()) or 1.0
            name = max(share, key=share.get)
            kind = name if share[name] / total > 0.9 else "mixed"
        rows.append({"mode": k + 1, "freq_hz": float(f), "type": kind})
    return rows
