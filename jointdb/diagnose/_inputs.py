"""Checking a recording's values before diagnosis: non-finite frequencies, values or coherence
(refused naming the recording, the FRF entry and the lines, or masked on request), overflow markers
(±1.8e308, an Inf as some UFF writers store it) and FRF entries that are exactly 0."""

from __future__ import annotations

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["finite_recording", "lines_text"]

#: |Re| or |Im| at or above this is an overflow marker, not a measurement.
_OVERFLOW = 1e300


def lines_text(freq: np.ndarray, idx: np.ndarray, limit: int = 3) -> str:
    """``line 937 (2345 Hz)`` / ``lines 937–940 (2345–2348.8 Hz), line 1200 (3000 Hz) and 4 more`` (1-based)."""
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    parts = []
    for r in runs[:limit]:
        if r.size == 1:
            parts.append(f"line {r[0] + 1} ({freq[r[0]]:g} Hz)")
        else:
            parts.append(f"lines {r[0] + 1}–{r[-1] + 1} ({freq[r[0]]:g}–{freq[r[-1]]:g} Hz)")
    more = sum(r.size for r in runs[limit:])
    return ", ".join(parts) + (f" and {more} more line{'s' if more > 1 else ''}" if more else "")


def finite_recording(m, k: int, mask: bool, notes: list[str]):
    """A :class:`Measurement` (the ``k``-th) as an :class:`FRF`, its coherence and the mask of non-finite entries (or None).

    Non-finite frequencies, values or coherence are refused (naming the
    recording, the FRF entry and the lines) unless ``mask``; masked lines get
    a placeholder interpolated from their finite neighbours and a note.
    """
    label = m.label or f"recording {k + 1}"
    src = m.frf
    coh = None if m.coherence is None else np.asarray(m.coherence, dtype=float)
    if isinstance(src, FRF) and (coh is None or np.all(np.isfinite(coh))) and not _overflow(src.values).any():
        _note_zeros(src, label, notes)
        return src, coh, None
    freq = np.asarray(src.freq, dtype=float)
    values = np.asarray(src.values, dtype=complex)
    outs, ins = tuple(Dof.parse(d) for d in src.outputs), tuple(Dof.parse(d) for d in src.inputs)
    if values.ndim == 1 and len(outs) == len(ins) == 1:
        values = values.reshape(-1, 1, 1)
    if freq.ndim != 1 or values.shape != (freq.size, len(outs), len(ins)):
        raise InputError(f"{label}: values have shape {values.shape}, expected (n_freq, n_out, n_in) = "
                         f"({freq.size}, {len(outs)}, {len(ins)})")
    if coh is not None and coh.ndim == 1 and coh.shape == freq.shape:
        coh = np.broadcast_to(coh[:, None, None], values.shape)
    if coh is not None and coh.shape != values.shape:
        raise InputError(f"{label}: coherence has shape {coh.shape}, the FRF has {values.shape}")
    bad_f = ~np.isfinite(freq)
    bad = ~np.isfinite(values) | _overflow(values) | (~np.isfinite(coh) if coh is not None else False)
    hint = "fix the recording, or pass mask_nonfinite=True (CLI: --mask-nonfinite) to give those lines zero weight"
    if bad_f.any():
        idx = np.flatnonzero(bad_f)
        if not mask:
            where = ", ".join(f"line {i + 1}" for i in idx[:3]) + (f" and {idx.size - 3} more" if idx.size > 3 else "")
            raise InputError(f"{label}: the frequency of {where} is {freq[idx[0]]} (not a number); {hint}")
        notes.append(f"{label}: {idx.size} line(s) with a non-finite frequency dropped "
                     f"({', '.join(str(i + 1) for i in idx[:5])}{' …' if idx.size > 5 else ''})")
    keep = ~bad_f
    freq, values, bad = freq[keep], values[keep], bad[keep]
    coh = coh[keep] if coh is not None else None
    if bad.any():
        entries = [(o, i) for o in range(len(outs)) for i in range(len(ins)) if bad[:, o, i].any()]
        o, i = entries[0]
        idx = np.flatnonzero(bad[:, o, i])
        what = "values" if (~np.isfinite(values[:, o, i]) | _overflow(values[:, o, i])).any() else "coherence"
        where = f"FRF {outs[o]}/{ins[i]}"
        if idx.size == freq.size:
            first = f"{where}: every {'value' if what == 'values' else 'coherence value'} is non-finite (NaN/Inf)"
        else:
            raw = values[idx, o, i] if what == "values" else coh[idx, o, i]
            kinds = "/".join(k for k, f in (("NaN", np.isnan), ("Inf", np.isinf),
                                            ("±1.8e308, an Inf as some UFF writers store it", _overflow))
                             if f(raw).any())
            first = (f"{where}: {idx.size} non-finite {what if idx.size > 1 or what != 'values' else 'value'} "
                     f"({kinds}) at {lines_text(freq, idx)}")
        others = f"; {len(entries) - 1} more FRF entr{'ies' if len(entries) > 2 else 'y'} too" \
            if len(entries) > 1 else ""
        if not mask:
            raise InputError(f"{label}: {first}{others}; {hint}")
        if bad.all():
            raise InputError(f"{label}: every value is non-finite (NaN/Inf); nothing to diagnose")
        notes.append(f"{label}: {int(bad.sum())} non-finite value(s) masked (zero weight): "
                     + "; ".join(f"FRF {outs[a]}/{ins[b]} at {lines_text(freq, np.flatnonzero(bad[:, a, b]))}"
                                 for a, b in entries[:4])
                     + (f"; and {len(entries) - 4} more FRF entries" if len(entries) > 4 else ""))
        fill = values.copy()
        for a, b in entries:  # a few entries; lines batched by np.interp
            good = ~bad[:, a, b]
            if good.any():
                fill[:, a, b] = np.interp(freq, freq[good], values[good, a, b].real) + \
                    1j * np.interp(freq, freq[good], values[good, a, b].imag)
            else:
                fill[:, a, b] = 1.0
        values = fill
        if coh is not None:
            coh = np.where(np.isfinite(coh), coh, 0.0)
    if freq.size == 0:
        raise InputError(f"{label}: no line has a finite frequency")
    frf = FRF(freq, values, outs, ins, src.quantity)
    _note_zeros(frf, label, notes, bad)
    return frf, coh, (bad if bad.any() else None)


def _overflow(values: np.ndarray) -> np.ndarray:
    """Finite values no FRF can have: ±1.8e308 (DBL_MAX) is how some UFF writers store an Inf."""
    v = np.asarray(values)
    return np.isfinite(v) & (np.maximum(np.abs(v.real), np.abs(v.imag)) >= _OVERFLOW)


def _note_zeros(frf: FRF, label: str, notes: list[str], skip: np.ndarray | None = None) -> None:
    """Exactly-zero values (above 0 Hz) get zero weight; say so (some UFF writers store a NaN as 0)."""
    zero = (frf.values == 0) & (frf.freq > 0)[:, None, None]
    if skip is not None:
        zero &= ~skip
    if not zero.any():
        return
    above = frf.freq > 0
    dead = [(o, i) for o in range(zero.shape[1]) for i in range(zero.shape[2])
            if above.any() and zero[above, o, i].all()]
    if dead:
        what = "every FRF" if len(dead) == zero.shape[1] * zero.shape[2] else \
            ", ".join(f"FRF {frf.outputs[o]}/{frf.inputs[i]}" for o, i in dead[:4]) + \
            (f" and {len(dead) - 4} more" if len(dead) > 4 else "")
        raise InputError(f"{label}: {what} is exactly 0 at every line (a disconnected channel or an empty "
                         "record); nothing to compare: record it again or leave that FRF out of the file")
    entries = [(o, i) for o in range(zero.shape[1]) for i in range(zero.shape[2]) if zero[:, o, i].any()]
    notes.append(f"{label}: {int(zero.sum())} value(s) exactly 0 get zero weight (some UFF writers store a NaN "
                 "as 0): " + "; ".join(f"FRF {frf.outputs[o]}/{frf.inputs[i]} at "
                                       f"{lines_text(frf.freq, np.flatnonzero(zero[:, o, i]))}"
                                       for o, i in entries[:4])
                 + (f"; and {len(entries) - 4} more FRF entries" if len(entries) > 4 else ""))
