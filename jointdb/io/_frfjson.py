"""The JSON form of an FRF: the wire format of the HTTP API (server and client).

``frf_json(frf) -> dict`` and ``frf_from_json(data) -> FRF``: frequencies in Hz, the
entries as separate real and imaginary parts in SI units, the unit label of every
entry. It lives with the other FRF formats so that the HTTP client reads it without
importing the server (or FastAPI).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.io._units import unit_label


def frf_json(frf: FRF) -> dict[str, Any]:
    """An FRF as JSON: frequencies in Hz, entries as real and imaginary parts in SI units.

    Parameters
    ----------
    frf : jointdb.frf.FRF
        The FRF, SI units, ``values`` of shape ``(n_freq, n_outputs, n_inputs)``.

    Returns
    -------
    dict
        ``quantity``, ``freq_hz`` (n_freq,), ``outputs``, ``inputs``, ``units``
        (n_outputs × n_inputs SI labels), ``real`` and ``imag`` (n_freq × n_outputs ×
        n_inputs nested lists).
    """
    return {
        "quantity": frf.quantity.value,
        "freq_hz": frf.freq.tolist(),
        "outputs": [str(d) for d in frf.outputs],
        "inputs": [str(d) for d in frf.inputs],
        "units": [[unit_label(frf.quantity, o, i) for i in frf.inputs] for o in frf.outputs],
        "real": np.ascontiguousarray(frf.values.real).tolist(),
        "imag": np.ascontiguousarray(frf.values.imag).tolist(),
    }


def frf_from_json(data: dict[str, Any]) -> FRF:
    """The inverse of :func:`frf_json`.

    Parameters
    ----------
    data : dict
        An FRF as :func:`frf_json` writes it; ``quantity`` defaults to receptance and
        ``units``, when given, must be what the quantity and the DOFs make them.

    Returns
    -------
    jointdb.frf.FRF

    Raises
    ------
    InputError
        Naming the field (``frf.real``, ``frf.units``, a missing field ...).
    """
    try:
        freq = np.asarray(data["freq_hz"], dtype=float)
        re_, im = np.asarray(data["real"], dtype=float), np.asarray(data["imag"], dtype=float)
        want = (freq.size, len(data["outputs"]), len(data["inputs"]))
        for part, arr in (("real", re_), ("imag", im)):  # no broadcasting: every entry given
            if arr.shape != want:
                raise InputError(f"frf.{part}: shape {arr.shape} must be (n_freq, n_outputs, n_inputs) = {want}")
        values = np.empty(want, dtype=np.complex128)  # not re + 1j·im, which turns a −0.0 real part into +0.0
        values.real, values.imag = re_, im
        frf = FRF(freq, values, tuple(data["outputs"]), tuple(data["inputs"]), data.get("quantity", "receptance"))
    except KeyError as exc:
        raise InputError(f"frf: missing field {exc.args[0]!r} (freq_hz, outputs, inputs, real, imag)") from None
    except InputError:
        raise
    except (TypeError, ValueError) as exc:
        raise InputError(f"frf: {' '.join(str(exc).split())}") from None
    if data.get("units") is not None:  # given: must be what the quantity and DOFs make them
        want_units = [[unit_label(frf.quantity, o, i) for i in frf.inputs] for o in frf.outputs]
        if data["units"] != want_units:
            raise InputError(f"frf.units: {str(data['units'])[:80]} do not match the quantity "
                             f"{frf.quantity.value} and the DOFs, which give {want_units}")
    return frf
