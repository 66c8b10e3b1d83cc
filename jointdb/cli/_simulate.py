"""CLI: ``jointdb simulate`` — time-domain milling of a tool tip (thin: read file, call use case, render)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from jointdb.cli._output import emit, message, write_rows
from jointdb.cli._options import PlotsOpt
from jointdb.errors import InputError

#: Largest revolutions / steps accepted (bound run time).
MAX_REVOLUTIONS = 5000
MAX_CUTS = 200


def _numbers(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise InputError(f"{option}: expected comma-separated numbers, got {text!r}") from None
    if not values:
        raise InputError(f"{option}: give at least one number")
    return values


def simulate(
    frf_file: Path = typer.Argument(..., help="Tool-tip FRF (UFF58, HDF5 or CSV) with the x and/or y driving points."),
    rpm: str = typer.Option(..., "--rpm", help="Spindle speed(s) in rpm, comma-separated."),
    depth: str = typer.Option(..., "--depth", help="Axial depth(s) of cut in m, one per speed (or one for all)."),
    teeth: int = typer.Option(2, "--teeth", help="Number of teeth."),
    kt: float = typer.Option(..., "--kt", help="Tangential cutting coefficient K_t in N/m²."),
    kr: float = typer.Option(..., "--kr", help="Radial cutting coefficient K_r in N/m²."),
    immersion: float = typer.Option(1.0, "--immersion", help="Radial immersion a_e/D in (0, 1]."),
    up: bool = typer.Option(False, "--up", help="Up-milling (default: down-milling)."),
    feed: float = typer.Option(1e-4, "--feed", help="Feed per tooth in m."),
    revolutions: int = typer.Option(200, "--revolutions", help="Simulated spindle revolutions (>= 8)."),
    runout: Optional[str] = typer.Option(None, "--runout", help="Radial runout per tooth in m, comma-separated."),
    modes: Optional[int] = typer.Option(None, "--modes", help="Modes to fit per direction (default: automatic)."),
    plots: PlotsOpt = None,
    out: Optional[Path] = typer.Option(None, "--out", help="Write the per-cut summary to .csv or .json."),
    as_json: bool = typer.Option(False, "--json", help="Machine-readable output (SI units)."),
) -> None:
    """Simulate milling in the time domain: chatter or not, chatter frequency, forces, vibration, SLE.

    The tip's x/y modes are fitted (pLSCF), the regenerative cut is integrated with the tool
    leaving the cut (and optional runout), and chatter is judged on the once-per-period
    samples of the tip. --plots DIR writes one figure per cut.

    Example: jointdb simulate tip.uff --rpm 12000 --depth 1e-3 --teeth 4 --kt 7.96e8 --kr 1.69e8 --immersion 0.5
    """
    from jointdb.cli._tip_inputs import read_tool_tip
    from jointdb.stability import MillingCut
    from jointdb.usecases import simulate_tip

    speeds = _numbers(rpm, "--rpm")
    depths = _numbers(depth, "--depth")
    if len(depths) == 1:
        depths = depths * len(speeds)
    if len(depths) != len(speeds):
        raise InputError(f"--depth: give one depth per speed ({len(speeds)}) or one for all, got {len(depths)}")
    if len(speeds) > MAX_CUTS:
        raise InputError(f"--rpm: at most {MAX_CUTS} cuts at once, got {len(speeds)}")
    if revolutions > MAX_REVOLUTIONS:
        raise InputError(f"--revolutions {revolutions}: the limit is {MAX_REVOLUTIONS}")
    if out is not None and out.suffix.lower() not in (".csv", ".json"):
        raise InputError(f"--out {out.name}: use .csv or .json")
    frf, notes = read_tool_tip(frf_file)
    for line in notes:
        message(line)
    cut = MillingCut(teeth, kt, kr, immersion, not up)
    sim = simulate_tip(frf, cut, speeds, depths, feed_per_tooth_m=feed, revolutions=revolutions,
                       runout_m=_numbers(runout, "--runout") if runout else None, n_modes=modes)
    for name, nmse in sim.fit_quality.items():
        message(f"modal fit {name}: NMSE {nmse:.2e}")
    rows = [r.summary() for r in sim.results]
    if plots is not None:
        from jointdb.plots._simulate import plot_simulation

        plots.mkdir(parents=True, exist_ok=True)
        for r in sim.results:
            message(f"wrote {plot_simulation(r, plots / f'simulate-{r.spindle_speed_rpm:.0f}rpm-{r.depth_m * 1e6:.0f}um.png')}")
    if out is not None:
        write_rows(out, rows, kind="simulation", meta={"source": str(frf_file)})
        message(f"wrote {out}")
    if as_json:
        emit({"cuts": rows, "fit_nmse": sim.fit_quality, "notes": notes}, as_json=True)
        return
    emit([{"rpm": r["spindle_speed_rpm"], "depth_mm": r["depth_m"] * 1e3,
           "verdict": "chatter" if r["chatter"] else "stable", "statistic": r["statistic"],
           "chatter_freq_hz": r["chatter_freq_hz"], "max_force_n": r["max_force_n"],
           "vib_pp_x_um": r["vibration_pp_x_m"] * 1e6, "vib_pp_y_um": r["vibration_pp_y_m"] * 1e6,
           "sle_um": r["surface_location_error_m"] * 1e6} for r in rows],
         title=f"Time-domain milling, {teeth} teeth, a/D = {immersion:g}, {'up' if up else 'down'}-milling")


def register(app: typer.Typer) -> None:
    """Add ``simulate`` to the app."""
    app.command("simulate")(simulate)
