"""File formats for FRFs: UFF58 (pyuff), the HDF5 exchange file, CSV.

Everything returns or takes a :class:`jointdb.frf.FRF` in SI units with
positive direction labels. ``pyuff`` and ``h5py`` are imported lazily inside
the functions that need them, so ``import jointdb.io`` stays light.

UFF58 (universal file dataset 58, ASCII and binary 58b)
    ``read_uff58(path) -> list[UffRecord]`` — every dataset-58 record, signs
    normalised (−X read as +X with values negated), units SI (unit labels and
    dataset 164 honoured), notes in ``record.conversions``.
    ``read_frf_uff58(path, quantity=None, *, file_quantity=None, fill="error") -> FRF``
    — the FRF records as one full outputs × inputs matrix on one grid; names
    the missing pairs otherwise (``fill="reciprocity"`` fills from H[j, i]).
    ``import_uff58(...) -> UffImport`` — the same plus the notes of what was
    converted and which non-FRF records were skipped.
    ``frf_from_records(records, ...)`` — the grouping step alone;
    ``read_uff58_records(path)`` — the records before grouping (``UffFrfRecord`` each).
    ``coherence_from_records(records, frf)`` — the coherence records arranged like ``frf``.
    ``FUNCTION_TYPES`` — UFF58 function type numbers and their names.
    ``read_coherence_uff58(path, frf=None) -> ndarray | None`` — the
    coherence records (function type 6) as ``(n_freq, n_out, n_in)``.
    ``write_uff58(path, frf, binary=False, *, abscissa="auto", round_freq=False,
    coherence=None)`` — one record per entry (and one coherence record per
    entry when given); see :mod:`jointdb.io._uff58_write` for the
    precision of the format (binary is bit-exact; ASCII keeps 12 significant
    digits of values and 6 of frequencies, and refuses to round frequencies
    unless asked).

HDF5 exchange file (format ``jointdb-frf`` = ``HDF5_FORMAT``, version 1 = ``HDF5_FORMAT_VERSION``; layout in :mod:`jointdb.io._hdf5`)
    ``write_frf_hdf5(path, frf, attrs=None)``, ``read_frf_hdf5(path) -> FRF``,
    ``read_frf_hdf5_attrs(path) -> dict``, ``read_frf_hdf5_full(path) -> (FRF, dict)``.

CSV (layout in :mod:`jointdb.io._csv`)
    ``write_frf_csv(path, frf)``, ``read_frf_csv(path) -> FRF``.

JSON (the HTTP API's wire format; :mod:`jointdb.io._frfjson`)
    ``frf_json(frf) -> dict``, ``frf_from_json(data) -> FRF`` — frequencies in Hz,
    real and imaginary parts in SI units, the unit label of every entry.

Units
    ``unit_label(quantity, output, input) -> str`` — the SI unit of an entry,
    e.g. ``"m/s^2/N"``.

All writers are atomic: a temporary file in the target directory, fsync,
``os.replace``; a failure leaves the target as it was.
"""

from jointdb.io._csv import read_frf_csv, write_frf_csv
from jointdb.io._frfjson import frf_from_json, frf_json
from jointdb.io._hdf5 import (
    HDF5_FORMAT,
    HDF5_FORMAT_VERSION,
    read_frf_hdf5,
    read_frf_hdf5_attrs,
    read_frf_hdf5_full,
    write_frf_hdf5,
)
from jointdb.io._uff58_group import (
    UffImport,
    coherence_from_records,
    frf_from_records,
    import_uff58,
    read_coherence_uff58,
    read_frf_uff58,
)
from jointdb.io._uff58_read import FUNCTION_TYPES, UffFrfRecord, UffRecord, read_uff58
from jointdb.io._uff58_write import write_uff58
from jointdb.io._units import unit_label

#: Alias of :func:`read_uff58` (name used in the issue text).
read_uff58_records = read_uff58

__all__ = [
    "FUNCTION_TYPES",
    "HDF5_FORMAT",
    "HDF5_FORMAT_VERSION",
    "UffFrfRecord",
    "UffImport",
    "UffRecord",
    "frf_from_json",
    "frf_from_records",
    "frf_json",
    "import_uff58",
    "read_frf_csv",
    "read_frf_hdf5",
    "read_frf_hdf5_attrs",
    "read_frf_hdf5_full",
    "read_coherence_uff58",
    "coherence_from_records",
    "read_frf_uff58",
    "read_uff58",
    "read_uff58_records",
    "unit_label",
    "write_frf_csv",
    "write_frf_hdf5",
    "write_uff58",
]
