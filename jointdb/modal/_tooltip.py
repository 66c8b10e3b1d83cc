"""Tool-tip modal model for milling stability: one fit per x/y driving point."""

from __future__ import annotations

from collections.abc import Sequence

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.modal._lsfd import ModalFit, fit_modes
from jointdb.modal._model import ModalModel

__all__ = ["fit_tool_tip"]


def fit_tool_tip(
    frf: FRF,
    frf_y: FRF | None = None,
    n_modes: int | None = None,
    band: Sequence[float] | None = None,
    *,
    max_order: int = 30,
) -> tuple[ModalModel, tuple[ModalFit, ...]]:
    """Fit the x and y tool-tip driving points separately and combine them block-diagonally.

    ``frf`` holds the x (and/or y) driving point(s); ``frf_y`` optionally the y
    driving point in a separate container. The first driving point found per
    direction is used; cross terms are not modelled. The result feeds
    :func:`jointdb.stability.milling_lobes_sd`.

    Parameters
    ----------
    frf
        The x (and/or y) tool-tip driving point(s).
    frf_y
        The y driving point in a separate container.
    n_modes
        Modes per direction (None: every well-stabilised pole).
    band
        ``(f_min, f_max)`` [Hz] fitted.
    max_order
        Highest pLSCF model order.

    Returns
    -------
    (model, fits)
        The combined :class:`ModalModel` (outputs = inputs = the tip DOFs) and the
        per-direction :class:`ModalFit` results (diagram, quality).

    Raises
    ------
    InputError
        If no x or y driving-point FRF is present.
    """
    fits: list[ModalFit] = []
    seen: set[str] = set()
    for source in (frf, frf_y):
        if source is None:
            continue
        for d in source.outputs:
            if d.direction in ("x", "y") and d.direction not in seen and d in source.inputs:
                fits.append(fit_modes(source.select([d], [d]), n_modes=n_modes, band=band, max_order=max_order))
                seen.add(d.direction)
    if not fits:
        raise InputError(
            "no x or y driving-point FRF found (an entry whose output and input are the same x or y DOF); "
            "the tool-tip FRF is needed for milling stability"
        )
    return ModalModel.block_diagonal([f.model for f in fits]), tuple(fits)
