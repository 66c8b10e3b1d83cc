"""Diagnosing a model against recordings: read the recordings (with NaN/Inf lines kept as
gaps), attach their excitation levels, and locate and name what the model lacks."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

from jointdb.errors import InputError

__all__ = ["read_recording", "diagnose_recordings"]


def read_recording(path: Path):
    """FRF and (if the file has coherence records, UFF58 function type 6) the coherence.

    A file whose dataset-58 records hold NaN/Inf values (which the UFF reader
    refuses) is read with those lines marked non-finite, so that diagnosis
    names them or, with ``--mask-nonfinite``, gives them zero weight.

    Parameters
    ----------
    path
        A UFF58 file of recorded FRFs (and optionally coherences).

    Returns
    -------
    jointdb.diagnose.Measurement
        The recording with its coherence (or None) and non-finite lines marked.

    Raises
    ------
    NotFoundError
        The file does not exist.
    InputError
        The file cannot be read as UFF58.
    """
    from jointdb.diagnose import Measurement
    from jointdb.io import read_coherence_uff58, read_frf_uff58

    if not path.exists():
        from jointdb.errors import NotFoundError

        raise NotFoundError(f"recording {path}: no such file")
    try:
        frf = read_frf_uff58(path)
    except InputError:
        gaps = _nonfinite_records(path)
        if gaps is None:
            raise
        return _read_with_gaps(path, *gaps)
    coh = read_coherence_uff58(path, frf)  # None when the file has no coherence records
    return Measurement(frf=frf, coherence=coh, label=path.name)


def _nonfinite_records(path: Path):
    """``(datasets, {dataset index: non-finite value lines})`` of a universal file, or None if it has none."""
    import numpy as np
    import pyuff

    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception:  # pyuff raises bare Exception for every failure: the reader's own message stands
        return None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    bad = {}
    for k, d in enumerate(sets):
        if int(d.get("type", 0)) != 58:
            continue
        x, y = np.asarray(d.get("x"), dtype=float), np.asarray(d.get("data"))
        if x.shape != y.shape or not np.issubdtype(y.dtype, np.number):
            return None
        if not np.all(np.isfinite(x)):
            line = int(np.flatnonzero(~np.isfinite(x))[0]) + 1
            raise InputError(f"{path}: dataset #{k + 1}: the frequency of line {line} is {x[line - 1]}; "
                             "a line without a frequency cannot be used: fix the file")
        if not np.all(np.isfinite(y)):
            bad[k] = np.flatnonzero(~np.isfinite(y))
    return (sets, bad) if bad else None


def _read_with_gaps(path: Path, sets: list, bad: dict):
    """Read a universal file with NaN/Inf values through the ordinary reader (units, signs, grouping)
    by way of a copy with those values zeroed, and mark them non-finite again in the result."""
    import tempfile

    import numpy as np
    import pyuff

    from jointdb.diagnose import Measurement
    from jointdb.frf import Dof
    from jointdb.io import read_coherence_uff58, read_frf_uff58

    clean = []
    for k, d in enumerate(sets):
        if k in bad:
            d = dict(d)
            d["data"] = np.where(np.isfinite(d["data"]), d["data"], 0)
        clean.append(d)
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / path.name
        try:
            pyuff.UFF(str(copy)).write_sets(clean, mode="overwrite")
            frf = read_frf_uff58(copy)
            coh = read_coherence_uff58(copy, frf)
        except InputError as exc:
            raise InputError(str(exc).replace(str(copy), str(path))) from None
    values = frf.values.copy()
    coh = None if coh is None else coh.copy()
    oi = {d: i for i, d in enumerate(frf.outputs)}
    ii = {d: i for i, d in enumerate(frf.inputs)}
    for k, lines in bad.items():
        d = sets[k]
        try:
            out, inp = Dof.from_uff(d["rsp_node"], d["rsp_dir"])[0], Dof.from_uff(d["ref_node"], d["ref_dir"])[0]
        except (InputError, KeyError):
            continue  # a record the reader does not place in the FRF matrix
        if out in oi and inp in ii:
            if int(d.get("func_type", 0)) == 6:
                if coh is not None:
                    coh[lines, oi[out], ii[inp]] = np.nan
            else:
                # keep what the file held: an Inf is named as an Inf, a NaN as a NaN
                raw = np.asarray(d["data"])[lines]
                values[lines, oi[out], ii[inp]] = np.where(np.isinf(raw), np.inf, np.nan)
    return Measurement.from_arrays(frf.freq, values, frf.outputs, frf.inputs, frf.quantity, coh, label=path.name)


def diagnose_recordings(model: str | Path, recordings: Sequence[str | Path], *, mapping: dict[int, str] | None = None,
                        levels: Sequence[float] = (), band: Sequence[float] = (), combinations: bool = True,
                        mask_nonfinite: bool = False, say: Callable[[str], None] = lambda text: None):
    """Locate where a model and recordings disagree, name the missing physics and refit.

    Parameters
    ----------
    model : str or Path
        The nominal beam model file (``jointdb-beam-model/1``).
    recordings : sequence of str or Path
        Recorded FRFs (UFF58, with coherence records if any); several = several excitation levels.
    mapping : dict, optional
        Recording node -> model point name (default: by node number).
    levels : sequence of float
        Excitation level of each recording [N]; empty: 1, 2, … in the order given when there are several.
    band : sequence of float
        ``(fmin, fmax)`` in Hz, or empty for the recordings' whole band.
    combinations : bool
        Also fit combinations of explanations (default), not only single ones.
    mask_nonfinite : bool
        Give NaN/Inf lines zero weight (with a note) instead of refusing them.
    say : callable
        Called with each note for people (levels assumed, ...).

    Returns
    -------
    tuple
        The diagnosis (:func:`jointdb.diagnose.diagnose`'s result) and the nominal
        :class:`jointdb.fe.BeamModel` read from ``model``.

    Raises
    ------
    InputError
        Levels or band of the wrong length, bad files (naming them).
    """
    from jointdb.diagnose import diagnose
    from jointdb.diagnose_bench import single_blas_thread
    from jointdb.fe import load_model

    nominal = load_model(model)
    ms = [read_recording(Path(p)) for p in recordings]
    lv = list(levels)
    if lv and len(lv) != len(ms):
        raise InputError(f"--levels gives {len(lv)} values for {len(ms)} recordings")
    if len(ms) > 1 and not lv:
        say("several recordings and no --levels: taking them as levels 1, 2, … in the order given")
        lv = [float(i + 1) for i in range(len(ms))]
    if lv:
        ms = [dataclasses.replace(m, level=v) for m, v in zip(ms, lv)]
    if band and len(band) != 2:
        raise InputError(f"band needs two frequencies (fmin, fmax) in Hz, got {len(band)}")
    with single_blas_thread():
        result = diagnose(nominal, ms, mapping=mapping or {}, band=tuple(band) if band else (None, None),
                          combinations=combinations, mask_nonfinite=mask_nonfinite)
    return result, nominal
