"""The HDF5 exchange file for one FRF set (format ``jointdb-frf``, version 1).

Layout
------
Root attributes

=====================  ========================================================
``format``             ``"jointdb-frf"``
``format_version``     ``1`` (int); readers refuse newer versions
``quantity``           ``"receptance"``, ``"mobility"`` or ``"accelerance"``
``frequency_unit``     ``"Hz"``
``complex_convention`` ``"values[..., 0] = real part, values[..., 1] = imaginary part (float64)"``
``time_convention``    ``"x(t) = Re{X exp(+i omega t)}"`` (so mobility = iω·receptance)
``dof_convention``     DOF labels ``<node><direction>``, directions ``x y z rx ry rz``
                       (UFF58 codes 1..6), always positive
``units``              ``"SI"``
``software``           ``"jointdb <version>"``
``metadata``           JSON text of the caller's ``attrs`` (``"{}"`` if none)
=====================  ========================================================

Datasets

=============  ================================  ===============================
``freq``       float64 ``(n_freq,)``              Hz, strictly increasing
``values``     float64 ``(n_freq, n_out, n_in, 2)``  FRF, trailing axis real/imag
``outputs``    UTF-8 strings ``(n_out,)``          response DOF labels, e.g. ``"12x"``
``inputs``     UTF-8 strings ``(n_in,)``           excitation DOF labels
``units``      UTF-8 strings ``(n_out, n_in)``     SI unit of each entry, e.g. ``"m/s^2/N"``
=============  ================================  ===============================

``freq`` and ``values`` are chunked along frequency (whole output × input
blocks per chunk, about 256 KiB) with the shuffle, gzip (level 4) and
fletcher32 filters. A trailing real/imag axis (rather than h5py's complex
compound) keeps the file readable by any HDF5 tool (MATLAB, h5dump, Julia);
the reader also accepts a complex compound ``values`` of shape
``(n_freq, n_out, n_in)``.

The file is written atomically: a temporary file in the same directory,
fsync, ``os.replace``; a failure never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF, dofs
from jointdb.io._atomic import atomic_path
from jointdb.io._units import unit_label

HDF5_FORMAT = "jointdb-frf"
HDF5_FORMAT_VERSION = 1
_CHUNK_BYTES = 256 * 1024
#: Largest dataset read from an exchange file (200 000 lines x 20 x 20 entries is 1.2 GiB).
MAX_DATASET_BYTES = 2 * 2**30
_COMPLEX_CONVENTION = "values[..., 0] = real part, values[..., 1] = imaginary part (float64)"
_TIME_CONVENTION = "x(t) = Re{X exp(+i omega t)}"
_DOF_CONVENTION = "labels <node><direction>, directions x y z rx ry rz (UFF58 codes 1..6), always positive"


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (Path,)):
        return str(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON-serialisable")


def _metadata_json(attrs: dict | None) -> str:
    if attrs is None:
        return "{}"
    if not isinstance(attrs, dict):
        raise InputError(f"attrs must be a dict, got {type(attrs).__name__}")
    try:
        return json.dumps(attrs, sort_keys=True, allow_nan=False, default=_json_default)
    except (TypeError, ValueError) as exc:
        raise InputError(f"attrs must be JSON-serialisable (str keys, numbers, strings, lists): {exc}") from None


def _software() -> str:
    from jointdb import __version__

    return f"jointdb {__version__}"


def write_frf_hdf5(path: str | os.PathLike, frf: FRF, attrs: dict | None = None) -> None:
    """Write one FRF set as a ``jointdb-frf`` HDF5 file (layout in the module docstring).

    Parameters
    ----------
    path
        Target file; replaced atomically if it exists.
    frf
        The FRF; stored bit-exactly (float64 real and imaginary parts).
    attrs
        Free metadata (JSON-serialisable dict: provenance, conditions, ...),
        stored as JSON text in the ``metadata`` attribute; read back with
        :func:`read_frf_hdf5_attrs`. numpy scalars/arrays become numbers/lists.

    Raises
    ------
    InputError
        If ``frf`` is not an FRF, ``attrs`` is not JSON-serialisable, or the
        target directory does not exist. Nothing is written then.
    """
    import h5py  # lazy

    if not isinstance(frf, FRF):
        raise InputError(f"write_frf_hdf5 needs an FRF, got {type(frf).__name__}")
    meta = _metadata_json(attrs)
    n_freq, n_out, n_in = frf.shape
    row_bytes = n_out * n_in * 2 * 8
    rows = int(max(1, min(n_freq, _CHUNK_BYTES // row_bytes)))
    filters = dict(shuffle=True, compression="gzip", compression_opts=4, fletcher32=True)
    str_t = h5py.string_dtype("utf-8")
    units = np.array([[unit_label(frf.quantity, o, i) for i in frf.inputs] for o in frf.outputs], dtype=object)
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = HDF5_FORMAT
            f.attrs["format_version"] = np.int64(HDF5_FORMAT_VERSION)
            f.attrs["quantity"] = frf.quantity.value
            f.attrs["frequency_unit"] = "Hz"
            f.attrs["complex_convention"] = _COMPLEX_CONVENTION
            f.attrs["time_convention"] = _TIME_CONVENTION
            f.attrs["dof_convention"] = _DOF_CONVENTION
            f.attrs["units"] = "SI"
            f.attrs["software"] = _software()
            f.attrs["metadata"] = meta
            d = f.create_dataset("freq", data=frf.freq, chunks=(rows,), **filters)
            d.attrs["unit"] = "Hz"
            v = np.stack([frf.values.real, frf.values.imag], axis=-1)
            d = f.create_dataset("values", data=v, chunks=(rows, n_out, n_in, 2), **filters)
            d.attrs["quantity"] = frf.quantity.value
            d.attrs["axes"] = "frequency, output, input, (real, imag)"
            f.create_dataset("outputs", data=np.array([str(x) for x in frf.outputs], dtype=object), dtype=str_t)
            f.create_dataset("inputs", data=np.array([str(x) for x in frf.inputs], dtype=object), dtype=str_t)
            f.create_dataset("units", data=units, dtype=str_t)


def _open(path: str | os.PathLike):
    import h5py  # lazy

    p = Path(path)
    if not p.is_file():
        raise NotFoundError(f"HDF5 file {p} does not exist")
    try:
        f = h5py.File(p, "r")
    except (OSError, RuntimeError) as exc:
        raise InputError(f"{p}: not a readable HDF5 file ({exc})") from None
    try:
        fmt = _scalar_text(_attr(f, "format", p))
        if fmt != HDF5_FORMAT:
            shown = fmt if fmt is not None else "missing or not a string"
            raise InputError(f"{p}: not a jointdb FRF file (format attribute is {shown!r}, expected {HDF5_FORMAT!r})")
        version = _scalar_int(_attr(f, "format_version", p))
        if version is None or version < 1:
            raise InputError(f"{p}: missing or invalid format_version attribute (expected an integer >= 1)")
        if version > HDF5_FORMAT_VERSION:
            raise InputError(
                f"{p}: written in {HDF5_FORMAT} version {version}; this jointdb reads up to "
                f"version {HDF5_FORMAT_VERSION} (upgrade jointdb)"
            )
    except BaseException:
        f.close()
        raise
    return p, f


@contextlib.contextmanager
def _damaged(p: Path):
    """HDF5 library errors while walking the file's structure: the file is damaged (one line)."""
    try:
        yield
    except (OSError, RuntimeError, KeyError) as exc:
        raise InputError(f"{p}: damaged HDF5 file ({exc})") from None


def _attr(f, name: str, p: Path):
    """A root attribute, or ``None`` if absent; an attribute HDF5 cannot decode is an input error."""
    try:
        return f.attrs.get(name)
    except (OSError, RuntimeError, KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{p}: attribute {name!r} cannot be read ({exc})") from None


def _item(v):
    """``v``; for a numpy array of shape ``()`` or ``(1,)`` its one element, for a larger one None."""
    if isinstance(v, np.ndarray):
        return v.reshape(()).item() if v.shape in ((), (1,)) else None
    return v


def _scalar_text(v) -> str | None:
    """A string attribute's text (str or UTF-8 bytes, numpy scalars included), else ``None``."""
    v = _item(v)
    if isinstance(v, bytes):
        try:
            return v.decode("utf-8")
        except UnicodeDecodeError:
            return None
    return str(v) if isinstance(v, str) else None


def _scalar_int(v) -> int | None:
    """An integer attribute's value (a whole number, numpy scalars included), else ``None``."""
    v = _item(v)
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        return None
    if not np.isfinite(v) or int(v) != v:
        return None
    return int(v)


def _attr_str(f, name: str, p: Path) -> str:
    if name not in f.attrs:
        raise InputError(f"{p}: missing attribute {name!r}")
    v = _attr(f, name, p)
    text = _scalar_text(v)
    if text is None:
        raise InputError(f"{p}: attribute {name!r} must be a string, got {type(v).__name__}")
    return text


def _read_dataset(f, name: str, p: Path) -> np.ndarray:
    import h5py  # lazy

    if name not in f:
        raise InputError(f"{p}: missing dataset {name!r}")
    d = f[name]
    if not isinstance(d, h5py.Dataset):
        raise InputError(f"{p}: {name!r} must be a dataset, got a {type(d).__name__.lower()}")
    try:
        nbytes = int(np.prod(d.shape, dtype=float)) * d.dtype.itemsize if d.shape is not None else 0
    except TypeError:
        nbytes = 0
    if nbytes > MAX_DATASET_BYTES:
        raise InputError(f"{p}: dataset {name!r} declares shape {d.shape} ({nbytes / 2**30:.3g} GiB); the limit "
                         f"is {MAX_DATASET_BYTES / 2**30:g} GiB")
    try:
        return d[()]
    except OSError as exc:  # fletcher32 / gzip failure: the bytes on disk are damaged
        raise IntegrityError(f"{p}: dataset {name!r} failed its checksum or decompression ({exc}); "
                             "the file is corrupt") from None
    except (TypeError, ValueError, UnicodeDecodeError) as exc:  # a type h5py/numpy cannot read
        raise InputError(f"{p}: dataset {name!r} cannot be read ({exc})") from None


def _labels(raw: np.ndarray, name: str, p: Path):
    try:
        return dofs([x.decode() if isinstance(x, bytes) else str(x) for x in np.atleast_1d(raw)])
    except InputError as exc:
        raise InputError(f"{p}: dataset {name!r}: {exc}") from None


def read_frf_hdf5_full(path: str | os.PathLike) -> tuple[FRF, dict]:
    """Read a ``jointdb-frf`` HDF5 file: the FRF and the metadata dict.

    Parameters
    ----------
    path
        The HDF5 file.

    Returns
    -------
    frf : FRF
    attrs : dict
        The metadata given to :func:`write_frf_hdf5`.

    Raises
    ------
    NotFoundError
        If the file does not exist.
    InputError
        Not HDF5, not a jointdb FRF file, a newer format version, missing or
        malformed datasets or attributes (named), or a dataset declared larger
        than :data:`MAX_DATASET_BYTES`.
    IntegrityError
        If a chunk fails its fletcher32 checksum (corrupt file).
    """
    p, f = _open(path)
    with f, _damaged(p):
        quantity = _attr_str(f, "quantity", p)
        meta_text = _attr_str(f, "metadata", p) if "metadata" in f.attrs else "{}"
        freq = _read_dataset(f, "freq", p)
        raw = _read_dataset(f, "values", p)
        outputs = _labels(_read_dataset(f, "outputs", p), "outputs", p)
        inputs = _labels(_read_dataset(f, "inputs", p), "inputs", p)
    raw = np.asarray(raw)
    if not np.issubdtype(raw.dtype, np.number):
        raise InputError(f"{p}: dataset 'values' holds {raw.dtype} data; expected float64 (n_freq, n_out, n_in, 2)")
    if np.iscomplexobj(raw):
        values = raw.astype(np.complex128)
    elif raw.ndim == 4 and raw.shape[-1] == 2:
        values = raw[..., 0].astype(np.float64) + 1j * raw[..., 1].astype(np.float64)
    else:
        raise InputError(f"{p}: dataset 'values' has shape {raw.shape}; expected (n_freq, n_out, n_in, 2)")
    freq = np.asarray(freq)
    if not np.issubdtype(freq.dtype, np.number) or np.iscomplexobj(freq):
        raise InputError(f"{p}: dataset 'freq' holds {freq.dtype} data; expected float64 Hz")
    try:
        frf = FRF(freq, values, outputs, inputs, quantity)
    except InputError as exc:
        raise InputError(f"{p}: {exc}") from None
    return frf, _metadata(meta_text, p)


def read_frf_hdf5(path: str | os.PathLike) -> FRF:
    """Read the FRF of a ``jointdb-frf`` HDF5 file (errors as :func:`read_frf_hdf5_full`).

    Parameters
    ----------
    path
        The HDF5 file (``str`` or path).

    Returns
    -------
    FRF
        ``(n_freq, n_out, n_in)``, in the quantity the file states.
    """
    return read_frf_hdf5_full(path)[0]


def read_frf_hdf5_attrs(path: str | os.PathLike) -> dict:
    """The metadata dict given as ``attrs`` to :func:`write_frf_hdf5` (``{}`` if none).

    Checks that the file is a ``jointdb-frf`` file but does not read the
    data. The format's own attributes (``format``, ``quantity``, ...) are not
    mixed in.

    Parameters
    ----------
    path
        The HDF5 file; its datasets are not read.

    Returns
    -------
    dict
        The metadata, as JSON gave it back.
    """
    p, f = _open(path)
    with f, _damaged(p):
        text = _attr_str(f, "metadata", p) if "metadata" in f.attrs else "{}"
    return _metadata(text, p)


def _metadata(text: str, p: Path) -> dict:
    """The ``metadata`` attribute's JSON text as a dict (InputError naming the file if it is not JSON)."""
    try:
        return json.loads(text)
    except (ValueError, RecursionError):  # JSONDecodeError is a ValueError
        raise InputError(f"{p}: attribute 'metadata' is not valid JSON") from None
