"""Operations over the whole repository: integrity check, blob garbage collection, the nearest
query and interpolation, bundle export and import.

A mixin of :class:`jointdb.store.Repository`: it hands the repository's ``storage`` (the narrow
interfaces of :mod:`jointdb.store._access`) and ``load_frf`` to the query, bundle and maintenance
helpers.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from datetime import datetime
from typing import Any

from jointdb.store import _db
from jointdb.store._reports import CheckReport
from jointdb.store._records import as_utc
from jointdb.store._types import Conditions


class WholeRepository:
    """``check``, ``gc``, ``nearest``, ``interpolate``, ``export``, ``import_`` (see
    :class:`jointdb.store.Repository`)."""

    @_db.with_db_errors
    def check(self, verify_blobs: bool = True) -> CheckReport:
        """Walk every row and blob; report missing or corrupt data (``jointdb db check``).

        Parameters
        ----------
        verify_blobs
            Read and verify every blob (slow for a large store), not only that it exists.

        Returns
        -------
        CheckReport
        """
        from jointdb.store._maintenance import check

        return check(self.storage, verify_blobs)

    @_db.with_db_errors
    def gc(self, min_age_s: float = 3600.0, dry_run: bool = False) -> list[str]:
        """Remove blobs no row references (and stale temporaries) older than ``min_age_s``.

        Parameters
        ----------
        min_age_s
            Only blobs older than this [s] (a blob being written is not yet referenced).
        dry_run
            Report without removing.

        Returns
        -------
        list of str
            The blobs removed (or that would be).
        """
        from jointdb.store._maintenance import gc

        return gc(self.storage, min_age_s, dry_run)

    @_db.with_db_errors
    def nearest(self, joint_type: str, conditions: Conditions | Mapping[str, Any], k: int = 3,
                at: datetime | str | None = None, *, label: str | None = None, all_versions: bool = False,
                include_deprecated: bool = False):
        """The ``k`` versions of ``joint_type`` closest to ``conditions``.

        By default each joint's newest version that is not deprecated takes part; ``label``,
        ``all_versions`` and ``include_deprecated`` narrow or widen that. The distance (a
        weighted sum over materials, preload, torque and geometry, each normalised by the
        catalogued range) is defined in :mod:`jointdb.store._query`; a request outside the
        catalogued range of a condition warns :class:`OutsideCatalogueWarning`.

        Parameters
        ----------
        joint_type
            ``"tool-holder"``, ``"holder-spindle"``, ...
        conditions
            The request: a :class:`Conditions` or a mapping of its fields (torque in N·m,
            preload in N, geometry in m).
        k
            How many versions to return, >= 1.
        at
            A past instant (datetime or ISO 8601 text): answer as the catalogue stood then.
        label
            Only versions carrying this label (not with ``at``).
        all_versions
            Every version of each joint, not only its newest.
        include_deprecated
            Deprecated versions too.

        Returns
        -------
        list of Match
            Nearest first: ``version``, ``distance``, ``per_condition``, ``extrapolating``,
            ``outside_range``.

        Raises
        ------
        InputError
            ``k < 1``, bad conditions or label, or ``label`` with ``at``.
        NotFoundError
            No catalogued version of that type in the selection.

        Examples
        --------
        Three tool–holder joints catalogued at 40, 80 and 120 N·m; the two nearest to 100 N·m:

        >>> import os, tempfile
        >>> import numpy as np
        >>> from jointdb.coupling import spring_damper_joint
        >>> from jointdb.store import Conditions, Repository
        >>> repo = Repository(os.path.join(tempfile.mkdtemp(), "joints.sqlite"))
        >>> freq = np.linspace(100.0, 2000.0, 20)
        >>> for torque, k in [(40.0, 1e7), (80.0, 2e7), (120.0, 3e7)]:
        ...     _ = repo.catalogue(f"th-{torque:.0f}nm", "tool-holder",
        ...                        spring_damper_joint(freq, [k, k / 40], [50.0, 1.0], ["1x", "1ry"]),
        ...                        Conditions(("carbide", "steel"), torque_nm=torque), "spring-damper-planar")
        >>> matches = repo.nearest("tool-holder", Conditions(("carbide", "steel"), torque_nm=100.0), k=2)
        >>> [(m.version.name, m.extrapolating) for m in matches]
        [('th-120nm', False), ('th-80nm', False)]
        >>> matches[0].distance < matches[1].distance
        True
        >>> repo.close()
        """
        from jointdb.store._query import nearest

        return nearest(self.storage, joint_type, conditions, k, as_utc(at), label=label, all_versions=all_versions,
                       include_deprecated=include_deprecated)

    @_db.with_db_errors
    def interpolate(self, matches, conditions: Conditions | Mapping[str, Any] | None = None, *,
                    method: str = "axes"):
        """An interpolated joint between catalogued neighbours, in dynamic stiffness.

        Parameters
        ----------
        matches
            Candidates, e.g. from :meth:`nearest`; ``"axes"`` uses those that bracket the
            request along its condition axes, so pass the catalogued grid around it.
        conditions
            The request (None: inverse-distance weights).
        method
            ``"axes"`` (weights along each condition axis; torque and preload on a log scale)
            or ``"idw"`` (inverse distance).

        Returns
        -------
        InterpolatedJoint
            ``frf`` (receptance on the neighbours' common band), ``neighbours`` ``(name,
            version, weight)`` with weight > 0, ``conditions``. Not a catalogued joint.

        Raises
        ------
        InputError
            No matches, an unknown method, neighbours of different type, model kind or DOFs,
            or no common frequency band.
        NumericalError
            A neighbour's receptance is singular on some line.

        Examples
        --------
        Joints at 80 and 120 N·m with stiffness 2·10⁷ and 3·10⁷ N/m; at 100 N·m the weights
        are those of log-torque, ``ln(100/80) / ln(120/80)`` = 0.5503 for the 120 N·m joint,
        and the interpolated stiffness is the weighted mean:

        >>> import os, tempfile
        >>> import numpy as np
        >>> from jointdb.coupling import equivalent_stiffness_damping, spring_damper_joint
        >>> from jointdb.store import Conditions, Repository
        >>> repo = Repository(os.path.join(tempfile.mkdtemp(), "joints.sqlite"))
        >>> freq = np.linspace(100.0, 2000.0, 20)
        >>> for torque, k in [(80.0, 2e7), (120.0, 3e7)]:
        ...     _ = repo.catalogue(f"th-{torque:.0f}nm", "tool-holder",
        ...                        spring_damper_joint(freq, [k, k / 40], [50.0, 1.0], ["1x", "1ry"]),
        ...                        Conditions(("carbide", "steel"), torque_nm=torque), "spring-damper-planar")
        >>> request = Conditions(("carbide", "steel"), torque_nm=100.0)
        >>> joint = repo.interpolate(repo.nearest("tool-holder", request, k=2), request)
        >>> [(name, round(weight, 4)) for name, _, weight in joint.neighbours]
        [('th-120nm', 0.5503), ('th-80nm', 0.4497)]
        >>> w = np.log(100 / 80) / np.log(120 / 80)
        >>> k, c = equivalent_stiffness_damping(joint.frf)                   # N/m, N·m/rad per line
        >>> bool(np.allclose(k[:, 0], w * 3e7 + (1 - w) * 2e7))
        True
        >>> repo.close()
        """
        from jointdb.store._query import interpolate

        return interpolate(self.load_frf, matches, conditions, method=method)

    @_db.with_db_errors
    def export(self, names: Iterable[str] | None, path: str | os.PathLike, *, sign_key=None) -> dict[str, Any]:
        """Write joints (all versions, provenance, labels, states) to one HDF5 bundle.

        Parameters
        ----------
        names
            Joint names to export (None: all).
        path
            The bundle file to write.
        sign_key
            An Ed25519 private key (:func:`jointdb.store.load_private_key`) to sign the
            bundle with, or None.

        Returns
        -------
        dict
            Counts of what was written.
        """
        from jointdb.store._bundle import export_bundle

        return export_bundle(self.storage, names, path, sign_key)

    @_db.with_db_errors
    def import_(self, path, author: str | None = None, *, trusted_keys=(),
                require_signature: bool = False, force: bool = False) -> dict[str, Any]:
        """Import a bundle (a path or a verified ``Bundle``); identical versions are no-ops,
        conflicting ones raise ConflictError, and so does a new version that is not the same
        joint as the one before it (unless ``force``); any ``trusted_keys`` (or
        ``require_signature``) refuse a bundle not signed by one of them (Ed25519 public keys).

        Parameters
        ----------
        path
            The bundle file, or a verified ``Bundle``.
        author
            Recorded as who imported.
        trusted_keys
            Ed25519 public keys (:func:`jointdb.store.load_public_key`); the bundle must be
            signed by one of them when any is given.
        require_signature
            Refuse an unsigned bundle.
        force
            Accept a new version that is not the same joint as the one before it.

        Returns
        -------
        dict
            A summary: versions added, identical ones skipped.
        """
        from jointdb.store._bundle import import_bundle

        return import_bundle(self.storage, path, author, trusted_keys, require_signature, force)
