"""Aligning recordings with a model: DOF mapping, common band, coherence, fit lines."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["Measurement", "Observation", "RecordedArrays", "prepare"]

#: A model-error floor on the log-FRF residual (2 %): lines with excellent
#: coherence cannot dominate the fit because no model is better than this.
MODEL_FLOOR = 0.02
#: Lines with coherence below this are not used.
MIN_COHERENCE = 0.5
#: |Re| or |Im| at or above this is an overflow marker, not a measurement.
_OVERFLOW = 1e300


@dataclass(frozen=True)
class Measurement:
    """One recorded FRF set, optionally with coherence and the excitation level.

    Parameters
    ----------
    frf
        The recording (any quantity; converted to receptance).
    coherence
        ``(n_freq, n_out, n_in)`` or ``(n_freq,)`` ordinary coherence 0..1, or None.
    level
        Excitation amplitude (e.g. force [N]) of this recording, or None.
    label
        Free text (e.g. the file name) used in messages.
    """

    frf: FRF | RecordedArrays
    coherence: np.ndarray | None = None
    level: float | None = None
    label: str = ""

    @classmethod
    def from_arrays(cls, freq, values, outputs, inputs, quantity="receptance", coherence=None,
                    level: float | None = None, label: str = "") -> "Measurement":
        """A recording given as plain arrays, which may hold NaN/Inf lines (an :class:`FRF` refuses them).

        :func:`prepare` refuses the non-finite lines, naming them, or masks
        them with ``mask_nonfinite=True``.

        Parameters
        ----------
        freq
            Frequency lines [Hz], ``(n_freq,)``.
        values
            Complex FRF values, ``(n_freq, n_out, n_in)``.
        outputs, inputs
            DOF labels of the rows and columns.
        quantity
            ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
        coherence, level, label
            As for :class:`Measurement`.

        Returns
        -------
        Measurement
        """
        return cls(RecordedArrays(np.asarray(freq, dtype=float), np.asarray(values, dtype=complex),
                                  tuple(outputs), tuple(inputs), quantity), coherence, level, label)


@dataclass(frozen=True, eq=False)
class RecordedArrays:
    """Recorded FRF values as they came, unchecked (see :meth:`Measurement.from_arrays`)."""

    freq: np.ndarray
    values: np.ndarray
    outputs: tuple
    inputs: tuple
    quantity: str = "receptance"


@dataclass(frozen=True, eq=False)
class Observation:
    """Recordings aligned with the model on the selected fit lines.

    Attributes
    ----------
    freq
        The fit lines [Hz], ``(n_freq,)``.
    values
        Recorded receptance on them, ``(n_level, n_freq, n_out, n_in)``.
    weight
        ``1/σ`` of ``log H`` per value (from coherence, with the model floor; 0 for unusable
        lines), same shape.
    out_points, out_dirs
        Model point name and direction of each output.
    in_points, in_dirs
        Model point name and direction of each input.
    levels
        Excitation level of each recording (None when not given).
    labels
        Each recording's label.
    full_freq, full_values, full_weight
        The same on all recorded lines inside the band.
    notes
        What :func:`prepare` did beyond mapping (masked non-finite lines, resampling, lines
        cut to the common band), one sentence each.
    """

    freq: np.ndarray
    values: np.ndarray
    weight: np.ndarray
    out_points: tuple[str, ...]
    out_dirs: tuple[str, ...]
    in_points: tuple[str, ...]
    in_dirs: tuple[str, ...]
    levels: tuple[float | None, ...]
    labels: tuple[str, ...]
    full_freq: np.ndarray          # all recorded lines inside the band
    full_values: np.ndarray        # (n_level, n_full, n_out, n_in)
    full_weight: np.ndarray
    notes: tuple[str, ...] = ()    # what was masked, resampled or cut, one sentence each

    @property
    def model_points(self) -> list[str]:
        return sorted(set(self.out_points) | set(self.in_points))

    @property
    def dof_names(self) -> list[str]:
        return [f"{p}:{d}" for p, d in zip(self.out_points, self.out_dirs)]


def _point_for(dof: Dof, model, mapping: Mapping[int, str], what: str, label: str) -> str:
    names = [p.name for p in model.points]
    if dof.node in mapping:
        name = mapping[dof.node]
        if name not in names:
            raise InputError(f"--map {dof.node}={name}: the model has no point {name!r} (it has {', '.join(names)})")
        return name
    for p in model.points:
        if p.node == dof.node:
            return p.name
    raise InputError(
        f"{label}: {what} DOF {dof} has no point in the model (model points: "
        + ", ".join(f"{p.name}=node {p.node}" for p in model.points)
        + f"); map it with --map {dof.node}=<point name>"
    )


def roughness_sigma(values: np.ndarray, half_window: int = 10) -> np.ndarray:
    """σ of log H estimated from the data alone (no coherence available).

    The second difference of ``log H`` along frequency, ``r_k = log H_k −
    (log H_{k−1} + log H_{k+1})/2``, has variance 1.5 σ² for independent noise
    of σ per line; a running median of ``|r|`` over ±``half_window`` lines
    (robust against the curvature of the few lines at a resonance) gives σ.
    """
    import scipy.ndimage

    lv = np.log(np.where(np.abs(values) > 0, values, 1e-300))
    r = np.zeros(values.shape)
    r[1:-1] = np.abs(lv[1:-1] - 0.5 * (lv[:-2] + lv[2:]))
    r[0], r[-1] = r[1], r[-2]
    med = scipy.ndimage.median_filter(r, size=(2 * half_window + 1,) + (1,) * (values.ndim - 1), mode="nearest")
    # median of |N(0, 1.5σ²)| (complex: both parts) ≈ 1.1774 · sqrt(1.5/2) σ
    return med / (1.1774 * np.sqrt(0.75))


def _sigma_from_coherence(coh: np.ndarray) -> np.ndarray:
    """σ of log H from ordinary coherence: ``σ² = (1 − γ²)/γ²`` (noise on the response)."""
    g = np.clip(coh, 1e-6, 1.0)
    return np.sqrt((1.0 - g) / g)


def _lines_text(freq: np.ndarray, idx: np.ndarray, limit: int = 3) -> str:
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


def _finite(m: Measurement, k: int, mask: bool, notes: list[str]):
    """The recording as an :class:`FRF` plus its coherence and the mask of non-finite entries (or None).

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
                     f"({kinds}) at {_lines_text(freq, idx)}")
        others = f"; {len(entries) - 1} more FRF entr{'ies' if len(entries) > 2 else 'y'} too" \
            if len(entries) > 1 else ""
        if not mask:
            raise InputError(f"{label}: {first}{others}; {hint}")
        if bad.all():
            raise InputError(f"{label}: every value is non-finite (NaN/Inf); nothing to diagnose")
        notes.append(f"{label}: {int(bad.sum())} non-finite value(s) masked (zero weight): "
                     + "; ".join(f"FRF {outs[a]}/{ins[b]} at {_lines_text(freq, np.flatnonzero(bad[:, a, b]))}"
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
                                       f"{_lines_text(frf.freq, np.flatnonzero(zero[:, o, i]))}"
                                       for o, i in entries[:4])
                 + (f"; and {len(entries) - 4} more FRF entries" if len(entries) > 4 else ""))


def _cut_notes(frfs, labels, lo: float, hi: float) -> list[str]:
    """Say what each recording loses by cutting all to their common range ``lo``–``hi``."""
    out = []
    for frf, label in zip(frfs, labels):
        cut = (frf.freq < lo) | (frf.freq > hi)
        if not cut.any():
            continue
        ind = indicator(frf.values)
        top = ind.max()
        lost = [frf.freq[i] for i in peak_indices(frf.freq, frf.values) if cut[i] and ind[i] >= 0.01 * top]
        sides = []
        if (frf.freq < lo).any():
            sides.append(f"below {lo:g} Hz")
        if (frf.freq > hi).any():
            sides.append(f"above {hi:g} Hz")
        out.append(f"{label}: {int(cut.sum())} line(s) {' and '.join(sides)} dropped, outside the range all "
                   f"recordings share ({lo:g}–{hi:g} Hz)"
                   + (f", including recorded peak(s) at {', '.join(f'{f:.0f}' for f in lost)} Hz" if lost else ""))
    return out


def prepare(model, measurements: Sequence[Measurement], mapping: Mapping[int, str] | None = None,
            band: tuple[float | None, float | None] = (None, None), lines_per_mode: int = 36,
            background_lines: int = 40, model_freqs: Sequence[float] = (),
            mask_nonfinite: bool = False) -> Observation:
    """Map, check and thin the recordings for diagnosis.

    Parameters
    ----------
    model
        The nominal :class:`jointdb.fe.BeamModel`.
    measurements
        One or more :class:`Measurement` (several = several excitation levels,
        same DOFs).
    mapping
        ``{recording node: model point name}``; by default a recording node
        maps to the model point with that ``node`` number.
    band
        Optional ``(fmin, fmax)`` [Hz].
    lines_per_mode, background_lines
        Thinning: recorded lines kept around every recorded and model peak,
        and log-spaced lines elsewhere.
    model_freqs
        Natural frequencies of the nominal model [Hz] (to keep lines around them).
    mask_nonfinite
        Give NaN/Inf lines (values, coherence; a non-finite frequency drops
        its line) zero weight instead of refusing them; ``Observation.notes``
        says how many were masked and where.

    Returns
    -------
    Observation
        With ``notes``: masked lines, recordings interpolated onto the first
        one's lines, lines cut to the range all recordings share (and the
        recorded peaks lost with them).

    Raises
    ------
    InputError
        No recordings; non-finite values (naming recording, FRF entry and
        lines) unless ``mask_nonfinite``; DOFs that differ between recordings
        or have no model point; directions the model lacks; no common
        frequency range; no line with usable coherence.
    """
    mapping = dict(mapping or {})
    if not measurements:
        raise InputError("no recording given: pass at least one FRF file")
    notes: list[str] = []
    checked = [_finite(m, k, mask_nonfinite, notes) for k, m in enumerate(measurements)]
    labels = [m.label or f"recording {k + 1}" for k, m in enumerate(measurements)]
    frfs = [c[0] for c in checked]
    first = frfs[0]
    for frf, lab in zip(frfs[1:], labels[1:]):
        if frf.outputs != first.outputs or frf.inputs != first.inputs:
            raise InputError(
                f"{lab}: its DOFs ({', '.join(map(str, frf.outputs))} / "
                f"{', '.join(map(str, frf.inputs))}) differ from the first recording's; "
                "several recordings must be the same test at different excitation levels"
            )
    label = labels[0]
    outs, ins = _model_points(first, model, mapping, label)
    lo, hi = _common_band(frfs, labels, band, notes)
    base = first.freq[(first.freq >= lo) & (first.freq <= hi) & (first.freq > 0)]
    if base.size < 8:
        raise InputError(f"only {base.size} recorded lines between {lo:g} and {hi:g} Hz; need at least 8")
    vals, wts = [], []
    for (frf0, coh, bad), lab in zip(checked, labels):
        v, w = _on_base_lines(frf0.to("receptance"), coh, bad, base, lab, label, (lo, hi), notes)
        vals.append(v)
        wts.append(w)
    values = np.stack(vals)
    weight = np.stack(wts)

    sel = _fit_lines(base, values, weight, lines_per_mode, background_lines, model_freqs)
    return Observation(
        freq=base[sel], values=values[:, sel], weight=weight[:, sel],
        out_points=tuple(outs), out_dirs=tuple(d.direction for d in first.outputs),
        in_points=tuple(ins), in_dirs=tuple(d.direction for d in first.inputs),
        levels=tuple(m.level for m in measurements), labels=tuple(m.label for m in measurements),
        full_freq=base, full_values=values, full_weight=weight, notes=tuple(notes),
    )


def _model_points(first, model, mapping: dict, label: str) -> tuple[list[str], list[str]]:
    """The model point of each output and input DOF of the recordings (InputError for a direction
    the model lacks or a DOF with no point)."""
    dirs_ok = ("x", "ry") if model.kind == "planar" else ("x", "y", "z", "rx", "ry", "rz")
    for d in (*first.outputs, *first.inputs):
        if d.direction not in dirs_ok:
            raise InputError(f"{label}: DOF {d} is in direction {d.direction!r}, which a {model.kind} model "
                             f"does not have ({', '.join(dirs_ok)})")
    outs = [_point_for(d, model, mapping, "output", label) for d in first.outputs]
    ins = [_point_for(d, model, mapping, "input", label) for d in first.inputs]
    return outs, ins


def _common_band(frfs, labels, band, notes: list[str]) -> tuple[float, float]:
    """The frequency range all recordings share, within ``band``; notes on the lines cut from each."""
    common_lo = max(frf.freq[0] for frf in frfs)
    common_hi = min(frf.freq[-1] for frf in frfs)
    lo, hi = common_lo, common_hi
    if band[0] is not None:
        lo = max(lo, band[0])
    if band[1] is not None:
        hi = min(hi, band[1])
    if not hi > lo:
        raise InputError(
            "the recordings share no frequency range"
            + (f" with the requested band {band[0]}–{band[1]} Hz" if any(b is not None for b in band) else "")
            + ": " + "; ".join(f"{lab}: {frf.freq[0]:g}–{frf.freq[-1]:g} Hz" for frf, lab in zip(frfs, labels))
        )
    if len(frfs) > 1:
        notes += _cut_notes(frfs, labels, common_lo, common_hi)
    return lo, hi


def _on_base_lines(frf, coh, bad, base: np.ndarray, lab: str, label: str, band: tuple[float, float],
                   notes: list[str]):
    """One recording (receptance) on the first recording's lines ``base`` — taken where they are its own
    lines, else interpolated (noted) — and the weight of each value (0 where unusable)."""
    idx = np.searchsorted(frf.freq, base).clip(0, frf.freq.size - 1)
    same = bool(np.allclose(frf.freq[idx], base, rtol=1e-12, atol=0.0))   # base lines are recorded lines
    if same:
        v = frf.values[idx]
        n_in = int(((frf.freq >= base[0]) & (frf.freq <= base[-1])).sum())
        if n_in > base.size:
            notes.append(f"{lab}: only {base.size} of its {n_in} lines between {base[0]:g} and {base[-1]:g} Hz "
                         f"are used (those on the grid of {label}); the others are dropped")
    else:
        inside = (frf.freq >= base[0]) & (frf.freq <= base[-1])
        df = np.median(np.diff(frf.freq)) if frf.freq.size > 1 else 0.0
        df0 = np.median(np.diff(base)) if base.size > 1 else 0.0
        notes.append(f"{lab}: its {int(inside.sum())} lines between {base[0]:g} and {base[-1]:g} Hz "
                     f"(spacing {df:.4g} Hz) were interpolated linearly onto the {base.size} lines of "
                     f"{label} (spacing {df0:.4g} Hz)"
                     + ("; its grid is coarser, so resonance peaks lose height" if df > 1.01 * df0 else ""))
        v = frf.resample(base).values

    def on_base(a, cast=float):
        """Per-entry arrays ``a`` (on the recording's lines) on the base lines."""
        if same:
            return a[idx]
        return np.stack([np.interp(base, frf.freq, c.astype(cast)) for c in a.reshape(a.shape[0], -1).T],
                        -1).reshape(v.shape)

    if bad is not None:
        bad = bad[idx] if same else on_base(bad) > 0
    if coh is not None:
        if coh.ndim == 1:
            coh = np.broadcast_to(coh[:, None, None], frf.values.shape) if coh.shape == frf.freq.shape else coh
        if coh.shape != frf.values.shape:
            raise InputError(f"{lab}: coherence has shape {coh.shape}, the FRF has {frf.values.shape}")
        coh = on_base(coh, coh.dtype)
        sigma = _sigma_from_coherence(coh)
        usable = coh >= MIN_COHERENCE
        if bad is not None:
            usable &= ~bad
        if usable.mean() < 0.1:
            raise InputError(
                f"{lab}: only {100 * usable.mean():.0f} % of the lines between "
                f"{band[0]:g} and {band[1]:g} Hz have coherence >= {MIN_COHERENCE}; no usable data to diagnose"
            )
    else:
        sigma = roughness_sigma(v)
        usable = sigma < 1.0
        if bad is not None:
            usable &= ~bad
    w = np.where(usable & np.isfinite(v) & (np.abs(v) > 0), 1.0 / np.sqrt(sigma**2 + MODEL_FLOOR**2), 0.0)
    if not w.any():
        raise InputError(f"{lab}: no usable line between {band[0]:g} and {band[1]:g} Hz")
    return np.where(w > 0, v, 1.0), w


def peak_indices(freq: np.ndarray, values: np.ndarray, weight: np.ndarray | None = None) -> np.ndarray:
    """Indices of resonance peaks of a set of FRFs ``(n_freq, n_out, n_in)``.

    Peaks of the sum over FRFs of the magnitude normalised by each FRF's
    median (a CMIF-like indicator), with a prominence of 6 dB.
    """
    import scipy.signal

    ind = np.log(indicator(values, weight) + 1e-300)
    idx, _ = scipy.signal.find_peaks(ind, prominence=np.log(2.0))
    return idx


def indicator(values: np.ndarray, weight: np.ndarray | None = None) -> np.ndarray:
    """CMIF-like peak indicator ``(n_freq,)``: Σ over FRFs of |H| / median |H|,
    each line counted in proportion to its weight (noisy lines fade out)."""
    mag = np.abs(values)
    if weight is None:
        trust = np.ones(mag.shape)
    else:
        trust = np.clip(weight / (0.5 * weight.max(axis=0, keepdims=True) + 1e-300), 0.0, 1.0)
    med = np.ma.median(np.ma.masked_where(trust <= 0.5, mag), axis=0)      # masked where no line is trusted
    med = np.ma.filled(med.astype(float), 0.0)[None]
    med = np.where(med > 0, med, mag.max(axis=0, keepdims=True) + 1e-300)
    return np.sum(trust * mag / med, axis=(1, 2))


def _fit_lines(freq, values, weight, per_mode, background, model_freqs):
    keep = np.zeros(freq.size, dtype=bool)
    centres = [freq[i] for lv in range(values.shape[0]) for i in peak_indices(freq, values[lv], weight[lv])]
    centres += [f for f in model_freqs if freq[0] <= f <= freq[-1]]
    for fc in centres:
        win = np.where(np.abs(freq - fc) <= 0.06 * fc)[0]
        if win.size > per_mode:
            win = win[np.unique(np.linspace(0, win.size - 1, per_mode).round().astype(int))]
        keep[win] = True
    bg = np.unique(np.searchsorted(freq, np.geomspace(freq[0], freq[-1], background)).clip(0, freq.size - 1))
    keep[bg] = True
    return np.where(keep)[0]
