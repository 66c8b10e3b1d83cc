"""Index arithmetic on DOF label tuples: label checks, block gathers, reciprocity."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from jointdb.errors import InputError
from jointdb.frf._labels import Dof


def _check_labels(outputs: tuple, inputs: tuple) -> None:
    """InputError unless both label tuples are non-empty and free of duplicates."""
    for name, labels in (("output", outputs), ("input", inputs)):
        if not labels:
            raise InputError(f"at least one {name} DOF is needed")
        if len(set(labels)) != len(labels):
            seen: set[Dof] = set()
            dup = next(d for d in labels if d in seen or seen.add(d))  # type: ignore[func-returns-value]
            raise InputError(f"duplicate {name} DOF {dup}")


def _take(values: np.ndarray, rows, cols) -> np.ndarray:
    """``values[:, rows][:, :, cols]`` in one gather: a new array ``(n_freq, len(rows), len(cols))``.

    Indexing the last two axes together copies only the requested entries
    (indexing them one after the other first copies whole rows).
    """
    r = np.asarray(rows, dtype=np.intp).reshape(-1, 1)
    c = np.asarray(cols, dtype=np.intp).reshape(1, -1)
    return values[:, r, c]


def reciprocal_index(frf, outs: Sequence[Dof], ins: Sequence[Dof]):
    """Where each entry of the block ``outs × ins`` sits in ``frf.values``, directly or by reciprocity.

    Parameters
    ----------
    frf : FRF
        The measured FRF (its label index is read, not its values).
    outs, ins
        The requested output and input DOFs.

    Returns
    -------
    (rows, cols), None
        Integer arrays ``(len(outs), len(ins))`` with
        ``frf.values[:, rows, cols]`` the requested block: ``H[o, i]`` where
        measured, else ``H[i, o]`` (reciprocity ``H_oi = H_io``).
    None, (o, i)
        The first requested pair known neither way.
    """
    oidx, iidx = frf._index["out"], frf._index["in"]
    rows = np.empty((len(outs), len(ins)), dtype=np.intp)
    cols = np.empty_like(rows)
    for r, o in enumerate(outs):  # loops over DOF pairs, not frequency lines
        for c, i in enumerate(ins):
            if o in oidx and i in iidx:
                rows[r, c], cols[r, c] = oidx[o], iidx[i]
            elif i in oidx and o in iidx:
                rows[r, c], cols[r, c] = oidx[i], iidx[o]
            else:
                return None, (o, i)
    return (rows, cols), None
