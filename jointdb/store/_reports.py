"""Result types of repository operations and the classification of write conflicts."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

from sqlalchemy.exc import IntegrityError as DBIntegrityError
from sqlalchemy.exc import OperationalError

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._types import JointVersion


@dataclass(frozen=True)
class CheckReport:
    """Result of :meth:`Repository.check`; ``ok`` when nothing is missing or corrupt.

    Attributes
    ----------
    versions_checked, blobs_checked
        How many version rows and blobs were checked.
    problems
        One line per missing or corrupt row or blob.
    orphan_blobs
        Blobs no row references (``gc`` removes them).
    temporaries
        Stale temporary files in the blob store.
    notes
        Other observations (e.g. missing immutability guards).
    """

    versions_checked: int
    blobs_checked: int
    problems: tuple[str, ...]
    orphan_blobs: tuple[str, ...] = ()
    temporaries: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return not self.problems


@dataclass(frozen=True)
class VersionDiff:
    """Differences between two versions (:meth:`Repository.diff`).

    Attributes
    ----------
    a, b
        The two versions, as ``"name vN"``.
    conditions
        Condition name → ``(value in a, value in b)`` for those that differ.
    fields
        Other record fields that differ, likewise.
    frf_entries
        Rows ``output``, ``input``, ``max_rel_diff`` = max over the common frequency lines of
        ``|H_b − H_a|`` divided by the peak ``|H_a|`` of that entry.
    max_relative_difference
        The largest ``max_rel_diff``, or None when the FRFs share no entry or line.
    same_blob
        Both versions store the same FRF.
    notes
        Further remarks (e.g. different DOFs or bands).
    """

    a: str
    b: str
    conditions: Mapping[str, tuple[Any, Any]]
    fields: Mapping[str, tuple[Any, Any]]
    frf_entries: tuple[Mapping[str, Any], ...]
    max_relative_difference: float | None
    same_blob: bool
    notes: tuple[str, ...] = field(default_factory=tuple)


def _is_unique_violation(exc: DBIntegrityError) -> bool:
    text = str(exc.orig).lower()
    sqlstate = getattr(exc.orig, "sqlstate", None)
    return sqlstate == "23505" or "unique" in text or "duplicate key" in text


def _is_transient(exc: OperationalError) -> bool:
    text = str(exc.orig).lower()
    sqlstate = getattr(exc.orig, "sqlstate", None)
    return "locked" in text or "busy" in text or sqlstate in ("40001", "40P01")


class Catalogued(NamedTuple):
    """What :meth:`Repository.catalogue_outcome` did.

    Attributes
    ----------
    version
        The :class:`JointVersion` written, or the identical latest one.
    created
        Whether it was written now (False: identical to the latest version, nothing written).
    """

    version: "JointVersion"
    created: bool
