"""Aligning recordings with a model: DOF mapping, common band, coherence, fit lines."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["Measurement", "Observation", "prepare"]

#: A model-error floor on the log-FRF residual (2 %): lines with excellent
#: coherence cannot dominate the fit because no model is better than this.
MODEL_FLOOR = 0.02
#: Lines with coherence below this are not used.
MIN_COHERENCE = 0.5


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

    frf: FRF
    coherence: np.ndarray | None = None
    level: float | None = None
    label: str = ""


@dataclass(frozen=True, eq=False)
class Observation:
    """Recordings aligned with the model on the selected fit lines.

    ``values`` is ``(n_level, n_freq, n_out, n_in)`` receptance, ``sigma`` the
    standard deviation of ``log H`` per entry (from coherence, with the model
    floor), ``weight = 1/sigma`` (0 for unusable lines). ``points`` are model
    point names of the outputs/inputs and ``directions`` their directions.
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


def prepare(model, measurements: Sequence[Measurement], mapping: Mapping[int, str] | None = None,
            band: tuple[float | None, float | None] = (None, None), lines_per_mode: int = 36,
            background_lines: int = 40, model_freqs: Sequence[float] = ()) -> Observation:
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

    Raises
    ------
    InputError
        No recordings; DOFs that differ between recordings or have no model
        point; directions the model lacks; no common frequency range; no line
        with usable coherence.
    """
    mapping = dict(mapping or {})
    if not measurements:
        raise InputError("no recording given: pass at least one FRF file")
    first = measurements[0].frf
    for m in measurements[1:]:
        if m.frf.outputs != first.outputs or m.frf.inputs != first.inputs:
            raise InputError(
                f"{m.label or 'recording'}: its DOFs ({', '.join(map(str, m.frf.outputs))} / "
                f"{', '.join(map(str, m.frf.inputs))}) differ from the first recording's; "
                "several recordings must be the same test at different excitation levels"
            )
    label = measurements[0].label or "recording"
    dirs_ok = ("x", "ry") if model.kind == "planar" else ("x", "y", "z", "rx", "ry", "rz")
    for d in (*first.outputs, *first.inputs):
        if d.direction not in dirs_ok:
            raise InputError(f"{label}: DOF {d} is in direction {d.direction!r}, which a {model.kind} model "
                             f"does not have ({', '.join(dirs_ok)})")
    outs = [_point_for(d, model, mapping, "output", label) for d in first.outputs]
    ins = [_point_for(d, model, mapping, "input", label) for d in first.inputs]

    lo = max(m.frf.freq[0] for m in measurements)
    hi = min(m.frf.freq[-1] for m in measurements)
    if band[0] is not None:
        lo = max(lo, band[0])
    if band[1] is not None:
        hi = min(hi, band[1])
    if not hi > lo:
        raise InputError(
            "the recordings share no frequency range"
            + (f" with the requested band {band[0]}–{band[1]} Hz" if any(b is not None for b in band) else "")
            + ": " + "; ".join(f"{m.label or i}: {m.frf.freq[0]:g}–{m.frf.freq[-1]:g} Hz"
                               for i, m in enumerate(measurements))
        )
    base = first.freq[(first.freq >= lo) & (first.freq <= hi) & (first.freq > 0)]
    if base.size < 8:
        raise InputError(f"only {base.size} recorded lines between {lo:g} and {hi:g} Hz; need at least 8")
    vals, wts = [], []
    for m in measurements:
        frf = m.frf.to("receptance")
        if not np.array_equal(frf.freq, first.freq):
            frf = frf.resample(base)
            idx = np.arange(base.size)
        else:
            idx = np.searchsorted(frf.freq, base)
        v = frf.values[idx]
        if m.coherence is not None:
            coh = np.asarray(m.coherence, dtype=float)
            if coh.ndim == 1:
                coh = np.broadcast_to(coh[:, None, None], frf.values.shape)
            if coh.shape != frf.values.shape:
                raise InputError(f"{m.label or 'recording'}: coherence has shape {coh.shape}, "
                                 f"the FRF has {frf.values.shape}")
            coh = coh[idx] if np.array_equal(m.frf.freq, first.freq) else \
                np.stack([np.interp(base, m.frf.freq, c) for c in coh.reshape(coh.shape[0], -1).T],
                         -1).reshape(v.shape)
            sigma = _sigma_from_coherence(coh)
            usable = coh >= MIN_COHERENCE
            if usable.mean() < 0.1:
                raise InputError(
                    f"{m.label or 'recording'}: only {100 * usable.mean():.0f} % of the lines between "
                    f"{lo:g} and {hi:g} Hz have coherence >= {MIN_COHERENCE}; no usable data to diagnose"
                )
        else:
            sigma = roughness_sigma(v)
            usable = sigma < 1.0
        w = np.where(usable & np.isfinite(v) & (np.abs(v) > 0), 1.0 / np.sqrt(sigma**2 + MODEL_FLOOR**2), 0.0)
        vals.append(np.where(w > 0, v, 1.0))
        wts.append(w)
    values = np.stack(vals)
    weight = np.stack(wts)

    sel = _fit_lines(base, values, weight, lines_per_mode, background_lines, model_freqs)
    return Observation(
        freq=base[sel], values=values[:, sel], weight=weight[:, sel],
        out_points=tuple(outs), out_dirs=tuple(d.direction for d in first.outputs),
        in_points=tuple(ins), in_dirs=tuple(d.direction for d in first.inputs),
        levels=tuple(m.level for m in measurements), labels=tuple(m.label for m in measurements),
        full_freq=base, full_values=values, full_weight=weight,
    )


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
