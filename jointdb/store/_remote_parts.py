"""The parts half of :class:`jointdb.store._remote.RemoteRepository`: parts of stacks (spindles,
holders, tools) catalogued, read, listed and labelled on a ``jointdb serve`` over HTTP, as
:class:`jointdb.store.Repository`'s parts store does locally.

A mixin: it uses the repository's ``_call``, ``_name`` and ``_post_idempotent``.
"""

from __future__ import annotations

from datetime import datetime

from jointdb.errors import InputError
from jointdb.io import frf_from_json, frf_json


class RemoteParts:
    """``add_part``, ``get_part``, ``resolve_part``, ``part_history``, ``list_parts``, ``label_part``,
    ``load_part_frf`` over HTTP (see :class:`jointdb.store._remote.RemoteRepository`)."""

    def add_part(self, name, kind, payload, *, frf=None, attributes=None, provenance=None, author=None,
                 label=None):
        """Catalogue a part on the server (the token's owner is the author).

        Parameters
        ----------
        name, kind, payload, frf, attributes, label
            As :meth:`jointdb.store.Repository.add_part`.
        provenance
            Only its ``input_files`` and ``method`` are sent; the server adds the rest.
        author
            Not sent: the server records the token's owner.

        Returns
        -------
        PartVersion
            The new version, or the latest one when its content is identical.
        """
        prov = dict(provenance or {})
        body = {"name": name, "kind": kind, "payload": dict(payload or {}), "attributes": dict(attributes or {}),
                "input_files": dict(prov.get("input_files") or {}),
                **({"method": prov["method"]} if prov.get("method") else {}), **({"label": label} if label else {})}
        if frf is not None:
            body["frf"] = frf_json(frf)
            body["frf"].pop("units", None)
        return part_from_json(self._call("POST", "/parts", json=body))

    def get_part(self, name, version=None, label=None):
        """One version of a part, as :meth:`jointdb.store.Repository.get_part` (the server verifies it).

        Parameters
        ----------
        name, version, label
            As :meth:`jointdb.store.Repository.get_part` (neither: the latest, one more request).

        Returns
        -------
        PartVersion
        """
        if version is not None and label is not None:
            raise InputError("give a version or a label, not both")
        if version is None and label is None:  # the latest: the newest entry of the versions list
            version = int(self._all(f"/parts/{self._name(name)}")[-1]["version"])
        which = str(int(version)) if version is not None else self._name(label)
        return part_from_json(self._call("GET", f"/parts/{self._name(name)}/{which}"))

    def resolve_part(self, ref):
        """The version a reference names, as :meth:`jointdb.store.Repository.resolve_part`.

        Parameters
        ----------
        ref
            ``"name@version"`` or ``"name@label"``.

        Returns
        -------
        PartVersion
        """
        from jointdb.store._part_records import parse_part_ref

        name, tail = parse_part_ref(ref)
        return self.get_part(name, version=tail) if isinstance(tail, int) else self.get_part(name, label=tail)

    def part_history(self, name):
        """Every version of a part (records with payloads: one request per version).

        Parameters
        ----------
        name
            As :meth:`jointdb.store.Repository.part_history`.

        Returns
        -------
        list of PartVersion
            Oldest first.
        """
        items = self._all(f"/parts/{self._name(name)}")
        return [self.get_part(name, int(d["version"])) for d in items]

    def list_parts(self, kind=None, *, family=None, machine=None):
        """The latest version of every part, as :meth:`jointdb.store.Repository.list_parts` (the server
        filters; then one request per part for its record with payload).

        Parameters
        ----------
        kind, family, machine
            As :meth:`jointdb.store.Repository.list_parts`.

        Returns
        -------
        list of PartVersion
        """
        params = {k: v for k, v in (("kind", kind), ("family", family), ("machine", machine)) if v is not None}
        return [self.get_part(d["name"], int(d["version"])) for d in self._all("/parts", **params)]

    def label_part(self, name, version, label, author=None):
        """Point ``label`` of a part at ``version``.

        Parameters
        ----------
        name, version, label
            As :meth:`jointdb.store.Repository.label_part`.
        author
            Not sent: the server records the token's owner.

        Returns
        -------
        PartVersion
        """
        return part_from_json(self._call("POST", f"/parts/{self._name(name)}/{int(version)}/labels",
                                         json={"label": label}))

    def load_part_frf(self, part):
        """A measured spindle's FRF set (the server verifies its blob against its digest).

        Parameters
        ----------
        part
            As :meth:`jointdb.store.Repository.load_part_frf`.

        Returns
        -------
        FRF
        """
        return frf_from_json(self._call("GET", f"/parts/{self._name(part.name)}/{int(part.version)}/frf"))


def part_from_json(d: dict):
    """A :class:`jointdb.store.PartVersion` from the API's JSON form of a part version."""
    from jointdb.store._part_records import PartVersion

    return PartVersion(d["name"], d["kind"], int(d["version"]), d["uuid"], datetime.fromisoformat(d["created_at"]),
                       d["author"], dict(d["attributes"]), dict(d["payload"]), d["blob_sha256"],
                       dict(d["provenance"]), d["parent_version"], d["record_sha256"], tuple(d["labels"]))
