"""Aligning recordings with a model: DOF mapping, common band, coherence, fit lines."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.diagnose._inputs import finite_recording
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["Measurement", "Observation", "RecordedArrays", "prepare"]

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
    checked = [finite_recording(m, k, mask_nonfinite, notes) for k, m in enumerate(measurements)]
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
