"""Guard a stack prediction against non-physical per-line joints (issue 22).

A per-line IRC joint (catalogued when constant k, c could not represent the contact) carries on
every line what its campaign's substructure models missed, including lines near their
antiresonances where it is noisy and its "damping" changes sign. Interpolated between
catalogued lines, or put into a stack unlike its campaign's, it can create a resonance that no
passive structure has: at its peak the driving-point receptance of the tool tip has a
*positive* imaginary part (a negatively damped mode; a passive one has Im H < 0 there, phase
between −180° and 0°). Such a prediction is wrong by an arbitrary amount (family B, S02-21:
+684 % peak), and no band built from the joints' spread covers it.

:func:`guarded` checks the nominal prediction's dominant peak in each plane. When it is not
passive, the catalogue's joints are replaced by their constant k, c fit over the fit band
(:func:`constant_joint`) — first only on the lines around the spurious peak (:func:`_local_repair`; the
per-line joint is kept elsewhere), else everywhere, one interface at a time (tool–holder first) and then
both — and the first passive prediction is kept; the replaced joint's resolution says so in its warnings.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from jointdb.frf import FRF

__all__ = ["PEAK_BAND_HZ", "non_passive_peaks", "constant_joint", "guarded"]

#: Lines searched for the dominant peak, and over which a fallback joint's constant k, c are fitted [Hz]
#: (the campaigns' fit band, ``options.fit_band``).
PEAK_BAND_HZ = (100.0, 5000.0)


#: Lines on each side of the dominant peak checked for Im H > 0: a sharp spurious resonance can fall between lines,
#: so the peak line alone may still show a negative imaginary part while its neighbours do not.
NEAR_PEAK_LINES = 3


def non_passive_peaks(freq: np.ndarray, tip: np.ndarray) -> list[str]:
    """Descriptions of the planes whose dominant tip peak is not passive (empty when all are).

    Parameters
    ----------
    freq : ndarray, shape (n_freq,)
        Lines [Hz].
    tip : ndarray, shape (n_freq, n, n)
        Tool-tip receptance [m/N]; its diagonal terms are driving points.

    Returns
    -------
    list[str]
        One text per diagonal term with Im H > 0 within :data:`NEAR_PEAK_LINES` lines of its largest |H|
        inside :data:`PEAK_BAND_HZ`.
    """
    f = np.asarray(freq, float)
    out = []
    for d, k, j in _bad_peaks(f, tip):
        h = tip[:, d, d]
        out.append(f"term {d + 1}: peak {abs(h[k]):.3g} m/N at {f[k]:.0f} Hz, phase "
                   f"{np.degrees(np.angle(h[j])):+.0f}° "
                   f"at {f[j]:.0f} Hz (a passive driving point lies between −180° and 0°)")
    return out


def _bad_peaks(f: np.ndarray, tip: np.ndarray) -> list[tuple[int, int, int]]:
    """``(term, peak line, line with Im H > 0)`` of each diagonal term whose dominant peak is not passive."""
    inside = (f >= PEAK_BAND_HZ[0]) & (f <= PEAK_BAND_HZ[1])
    out = []
    if not inside.any():
        return out
    for d in range(min(tip.shape[1], tip.shape[2])):
        h = tip[:, d, d]
        k = int(np.argmax(np.where(inside, np.abs(h), -np.inf)))
        near = slice(max(k - NEAR_PEAK_LINES, 0), k + NEAR_PEAK_LINES + 1)
        j = near.start + int(np.argmax(h[near].imag))
        if h[j].imag > 0:
            out.append((d, k, j))
    return out


def constant_joint(frf: FRF, band: tuple[float, float] = PEAK_BAND_HZ) -> FRF:
    """The joint's constant ``Z = K + iωC`` fit over ``band``, as a receptance on the joint's lines.

    ``K``: median of Re Z per entry; ``C``: median of Im Z / ω per entry; both symmetrised, ``C``'s negative
    eigenvalues set to 0 (a passive joint dissipates), so the fallback cannot create a negatively damped mode.

    Parameters
    ----------
    frf
        Joint receptance, square ``(n_freq, n, n)``.
    band
        ``(f_min, f_max)`` [Hz]; all lines when none falls inside.

    Returns
    -------
    FRF
        Same lines and DOFs.
    """
    f = frf.freq
    z = np.linalg.inv(frf.values)
    use = (f >= band[0]) & (f <= band[1])
    use = use if use.any() else np.ones(f.size, bool)
    w = 2 * np.pi * f
    k = np.median(z[use].real, axis=0)
    c = np.median(z[use].imag / w[use, None, None], axis=0)
    k, c = (k + k.T) / 2, (c + c.T) / 2
    val, vec = np.linalg.eigh(c)
    c = (vec * np.clip(val, 0.0, None)) @ vec.T
    return frf.replace(values=np.linalg.inv(k[None] + 1j * w[:, None, None] * c[None]))


#: A spurious peak's lines are repaired locally first: the joints' constant k, c replaces the per-line joint on the
#: lines within this fraction of the peak's frequency (the per-line joint is kept, and trusted, everywhere else; each
#: line of a prediction is independent of the others). Up to :data:`REPAIR_ROUNDS` spurious peaks are repaired so.
REPAIR_HALF_WIDTH = 0.05
REPAIR_ROUNDS = 3


def _local_repair(spec, joints, names, prediction, predict):
    """``(prediction, frfs, window text)`` with the joints ``names`` replaced by their constant fit on the lines around
    each non-passive dominant peak, or None when :data:`REPAIR_ROUNDS` windows do not make the tip passive."""
    frfs = {n: r.frf for n, r in joints.items() if r.frf is not None}
    const = {n: constant_joint(frfs[n]) for n in names}
    f = prediction.tip.freq
    windows: list[tuple[float, float]] = []
    trial = prediction
    for _ in range(REPAIR_ROUNDS):
        # only the planes whose peak is not passive; each joint's own lines inside a window, by frequency
        # (a joint's lines need not be the prediction's)
        windows += [(f[k] * (1 - REPAIR_HALF_WIDTH), f[k] * (1 + REPAIR_HALF_WIDTH))
                    for _, k, _ in _bad_peaks(f, trial.tip.values)]
        if not windows:
            return None
        for n in names:
            fj = frfs[n].freq
            on = np.any([(fj >= lo) & (fj <= hi) for lo, hi in windows], axis=0)
            frfs[n] = frfs[n].replace(values=np.where(on[:, None, None], const[n].values, joints[n].frf.values))
        trial = predict(spec, frfs)
        if not non_passive_peaks(trial.tip.freq, trial.tip.values):
            covered = np.any([(f >= lo) & (f <= hi) for lo, hi in windows], axis=0)
            lo, hi = min(w[0] for w in windows), max(w[1] for w in windows)
            return trial, frfs, f"{int(covered.sum())} lines within {lo:.0f}–{hi:.0f} Hz"
    return None


def guarded(spec, joints: Mapping, prediction, predict) -> tuple[object, dict]:
    """``(prediction, joints)``: the nominal ones when passive, else the first passive fallback (module docstring).

    Parameters
    ----------
    spec
        The stack (:class:`jointdb.stack.StackSpec`).
    joints
        Interface → :class:`jointdb.usecases.JointResolution`.
    prediction
        The nominal :class:`jointdb.stack.Prediction`.
    predict
        ``predict(spec, {interface: FRF})`` → Prediction, on the nominal's lines.

    Returns
    -------
    (Prediction, dict)
        The kept prediction and the resolutions (a replaced joint carries a warning saying why and how).
    """
    joints = dict(joints)
    bad = non_passive_peaks(prediction.tip.freq, prediction.tip.values)
    catalogued = [n for n, r in joints.items() if r.frf is not None and r.kind in ("catalogued", "query",
                                                                                   "interpolated")]
    if not bad or not catalogued:
        return prediction, joints
    repaired = _local_repair(spec, joints, catalogued, prediction, predict)
    if repaired is not None:
        trial, frfs, window = repaired
        _fall_back(joints, catalogued, frfs, bad, window)
        return trial, joints
    trials = [[n] for n in catalogued] + ([catalogued] if len(catalogued) > 1 else [])
    for names in trials:
        frfs = {n: r.frf for n, r in joints.items() if r.frf is not None}
        frfs.update({n: constant_joint(frfs[n]) for n in names})
        trial = predict(spec, frfs)
        if not non_passive_peaks(trial.tip.freq, trial.tip.values):
            _fall_back(joints, names, frfs, bad)
            return trial, joints
    for n in catalogued:
        note = (f"the tool-tip prediction is not passive ({'; '.join(bad)}) and constant k, c joints do not "
                "repair it: do not trust its peak")
        joints[n] = replace(joints[n], warnings=tuple(joints[n].warnings) + (note,))
    return prediction, joints


def _fall_back(joints: dict, names, frfs: Mapping, bad: list[str], window: str | None = None) -> None:
    """Put the fallback FRFs ``frfs`` of the joints ``names`` into ``joints``, each with its warning and
    description: on the lines of ``window`` (text) only, or (None) everywhere."""
    where = f"on {window} " if window else ""
    for n in names:
        note = (f"the catalogued joint's FRF gave a non-physical tool-tip resonance ({'; '.join(bad)}); "
                f"{where}its constant k, c fit over {PEAK_BAND_HZ[0]:g}–{PEAK_BAND_HZ[1]:g} Hz is used instead")
        joints[n] = replace(joints[n], frf=frfs[n], warnings=tuple(joints[n].warnings) + (note,),
                            constant_fallback=True,
                            description=f"{joints[n].description} (constant k, c fallback"
                                        f"{' near the spurious peak' if window else ''})")
