"""CLI: ``jointdb plan CAMPAIGN`` — which tap points determine the joint best (thin)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the app."""

    @app.command("plan")
    def plan_cmd(
        campaign: Annotated[Path, typer.Argument(help="Campaign file (JSON, format jointdb-campaign/1).")],
        points: Annotated[int, typer.Option("--measurements", help="FRFs per candidate set (response/excitation pairs).")] = 2,
        noise: Annotated[float, typer.Option("--noise", help="Relative noise of one averaged FRF (0.01 = 1 %).")] = 0.01,
        target: Annotated[float, typer.Option("--target", help="Wanted relative standard error of the target parameters.")] = 0.05,
        criterion: Annotated[str, typer.Option("--criterion", help="A (sum of target variances) or D (det of the information).")] = "A",
        targets: Annotated[Optional[str], typer.Option("--targets", help="Comma-separated parameter names (default: the rotational k, c of a planar joint; all for n-point).")] = None,
        as_json: Annotated[bool, typer.Option("--json", help="Machine-readable output.")] = False,
    ) -> None:
        """Rank candidate tap points by the expected joint-parameter variance (Fisher information).

        Example: jointdb plan fixtures/campaigns/th-steel-30nm/campaign.json --measurements 2 --target 0.02
        """
        from jointdb.cli._output import emit
        from jointdb.usecases import plan_measurements

        tg = [t.strip() for t in targets.split(",")] if targets else None
        result = plan_measurements(campaign, n_measurements=points, noise=noise, target=target, criterion=criterion,
                                   targets=tg)
        plan, current = result.plan, result.current
        if as_json:
            emit({"campaign": result.campaign, "criterion": plan.criterion, "noise": plan.noise, "target": plan.target,
                  "targets": plan.targets, "current": current, "ranked": plan.rows}, as_json=True)
            return
        rows = []
        for r in ([{**current, "measurements": ["(current) " + " + ".join(current["measurements"])]}]
                  if current else []) + plan.rows:
            row = {"measurements": " + ".join(r["measurements"])}
            row.update({f"σ {n}": f"{r['std_rel'][n]:.2%}" for n in plan.targets})
            row[f"averages for {plan.target:.0%}"] = r["averages"]
            rows.append(row)
        emit(rows, title=f"{result.campaign}: candidate measurements, best first ({plan.criterion}-optimal, "
                         f"{plan.noise:.0%} noise per average)")
