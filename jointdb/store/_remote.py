"""A joint database behind ``jointdb serve``, used like :class:`jointdb.store.Repository`.

``RemoteRepository(url, token)`` implements :class:`jointdb.store.JointStore` (``get``,
``history``, ``list_joints``, ``load_frf``, ``diff``, ``audit``, ``nearest``,
``interpolate``, ``catalogue``, ``catalogue_outcome``, ``label``, ``deprecate``; parts:
``add_part``, ``get_part``, ``list_parts``, ``part_history``, ``label_part``, ``load_part_frf``) over HTTP
and returns the same value types,
so ``jointdb --server URL query ...`` (or ``JOINTDB_SERVER=URL``, token from
``JOINTDB_TOKEN``) behaves as with a local database. The rules are applied once, by the
server's repository; HTTP errors come back as the same jointdb errors (404 NotFoundError,
409 ConflictError, 422 InputError, ...), with the server's one-line reason. It imports no
server code (the FRF's JSON form is :func:`jointdb.io.frf_json`). Public as :mod:`jointdb.client`.
"""

from __future__ import annotations

import warnings
from datetime import datetime
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from jointdb.errors import ConflictError, InputError, IntegrityError, JointdbError, NotFoundError
from jointdb.io import frf_from_json, frf_json
from jointdb.store._remote_parts import RemoteParts

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._reports import Catalogued

#: how often a catalogue request is sent again (same Idempotency-Key) after a connection error or a 503
RETRIES = 8
_ERRORS = {404: NotFoundError, 409: ConflictError, 422: InputError, 400: InputError, 413: InputError}


class RemoteRepository(RemoteParts):
    """The repository of a jointdb server (see the module docstring).

    Each method answers as the :class:`jointdb.store.Repository` method of the same name
    (the same parameters, documented there), over the server's HTTP API.

    Parameters
    ----------
    url
        The server's address, ``http(s)://host[:port]``.
    token
        An API token (sent as ``Authorization: Bearer``); None for an open server.
    timeout
        Seconds to wait for each response.
    """

    def __init__(self, url: str, token: str | None = None, timeout: float = 120.0):
        try:
            import httpx
        except ImportError:
            raise InputError("talking to a jointdb server needs httpx: pip install 'jointdb[server]'") from None
        if not url.startswith(("http://", "https://")):
            raise InputError(f"server URL {url[:80]!r} must start with http:// or https://")
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self.url = url.rstrip("/")
        self._http = httpx.Client(base_url=self.url + "/api/v1", headers=headers, timeout=timeout)
        self._httpx = httpx

    def close(self) -> None:
        self._http.close()

    def __enter__(self) -> "RemoteRepository":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"RemoteRepository({self.url!r})"

    # ------------------------------------------------------------------ http
    def _call(self, method: str, path: str, **kw) -> Any:
        try:
            r = self._http.request(method, path, **kw)
        except self._httpx.HTTPError as exc:
            raise InputError(f"cannot reach the jointdb server {self.url}: {type(exc).__name__}") from None
        return self._answer(r)

    def _answer(self, r) -> Any:
        """The JSON of a success, or the jointdb error of a failure (the server's one-line reason)."""
        if r.status_code < 300:
            return r.json()
        try:
            reason = r.json().get("error") or r.reason_phrase
        except ValueError:
            reason = r.reason_phrase
        if r.status_code in (401, 403):
            raise InputError(f"server {self.url}: {reason} (set JOINTDB_TOKEN)")
        cls = _ERRORS.get(r.status_code, IntegrityError if r.status_code == 500 else JointdbError)
        raise cls(f"server {self.url}: {reason}")

    @staticmethod
    def _name(name: str) -> str:
        return quote(str(name), safe="")

    #: rows asked for per page when a whole list is read
    PAGE = 500

    def _all(self, path: str, damaged: list | None = None, **params) -> list[dict]:
        """Every item of a paginated list: continued by the keyset cursor ``next`` where the list
        gives one (the joints list: each page costs the same), else by ``next_offset``."""
        items, position = [], {"offset": 0}
        while True:
            page = self._call("GET", path, params={**params, **position, "limit": self.PAGE})
            items.extend(page["items"])
            if damaged is not None and page.get("damaged"):
                from jointdb.store._records import DamagedVersion

                damaged.extend(DamagedVersion(str(d["name"]), int(d["version"]), str(d["error"]))
                               for d in page["damaged"])
            if page.get("next"):  # a page asked for by cursor has no next_offset (an offset counts from the start)
                position = {"after": page["next"]}
            elif page.get("next_offset") is not None:
                position = {"offset": page["next_offset"]}
            else:
                return items

    # ----------------------------------------------------------------- reads
    def get(self, name: str, version: int | None = None, at=None, label: str | None = None):
        """One version of a joint, as :meth:`jointdb.store.Repository.get`.

        Parameters
        ----------
        name, version, at, label
            As :meth:`jointdb.store.Repository.get`.

        Returns
        -------
        JointVersion
        """
        if version is not None:
            if label is not None:
                raise InputError("a label names one version now; do not combine it with --version or --at")
            data = self._call("GET", f"/joints/{self._name(name)}/versions/{int(version)}")
            if at is not None:
                from jointdb.store._records import as_utc

                if datetime.fromisoformat(data["created_at"]) > as_utc(at):
                    raise NotFoundError(f"joint {name!r} version {version} did not exist yet at {at}")
            return version_from_json(data)
        params = {k: v for k, v in (("label", label), ("at", str(at) if at is not None else None)) if v is not None}
        return version_from_json(self._call("GET", f"/joints/{self._name(name)}", params=params))

    def history(self, name: str, *, damaged: list | None = None) -> list:
        """All versions of a joint, oldest first, as :meth:`jointdb.store.Repository.history`.

        Parameters
        ----------
        name, damaged
            As :meth:`jointdb.store.Repository.history`.

        Returns
        -------
        list of JointVersion
        """
        return [version_from_json(v) for v in self._all(f"/joints/{self._name(name)}/history", damaged=damaged)]

    def list_joints(self, joint_type: str | None = None, include_deprecated: bool = True, *,
                    damaged: list | None = None) -> list:
        """As :meth:`jointdb.store.Repository.list_joints`; versions the server reports damaged are
        appended to ``damaged`` (when given) as ``DamagedVersion``.

        Parameters
        ----------
        joint_type, include_deprecated, damaged
            As :meth:`jointdb.store.Repository.list_joints`.

        Returns
        -------
        list of JointVersion
        """
        params = {"include_deprecated": include_deprecated}
        if joint_type:
            params["type"] = joint_type
        return [version_from_json(v) for v in self._all("/joints", damaged=damaged, **params)]

    def load_frf(self, version, number: int | None = None):
        """The joint FRF of a version (the server verifies it against its hash).

        Parameters
        ----------
        version, number
            As :meth:`jointdb.store.Repository.load_frf`.

        Returns
        -------
        FRF
        """
        name, v = (version.name, version.version) if number is None and hasattr(version, "name") else (version, number)
        return frf_from_json(self._call("GET", f"/joints/{self._name(name)}/versions/{int(v)}/frf",
                                        params={"format": "json"}))

    def diff(self, name: str, version_a: int, version_b: int | None = None, other: str | None = None):
        """Compare two versions, as :meth:`jointdb.store.Repository.diff`.

        Parameters
        ----------
        name, version_a, version_b, other
            As :meth:`jointdb.store.Repository.diff`.

        Returns
        -------
        VersionDiff
        """
        from jointdb.store._reports import VersionDiff

        params = {"a": version_a, **({"b": version_b} if version_b is not None else {}),
                  **({"other": other} if other else {})}
        d = self._call("GET", f"/joints/{self._name(name)}/diff", params=params)
        return VersionDiff(d["a"], d["b"], {k: (x["a"], x["b"]) for k, x in d["conditions"].items()},
                           {k: (x["a"], x["b"]) for k, x in d["fields"].items()}, tuple(d["frf_entries"]),
                           d["max_relative_difference"], d["same_blob"], tuple(d["notes"]))

    def audit(self, name: str | None = None, limit: int = 100) -> list[dict]:
        """The newest audit entries, newest first.

        Parameters
        ----------
        name
            Only entries of this joint (None: all).
        limit
            At most this many (the server answers at most 500).

        Returns
        -------
        list of dict
        """
        params = {"limit": min(int(limit), 500), **({"joint": name} if name else {})}
        return self._call("GET", "/audit", params=params)["items"]

    def nearest(self, joint_type: str, conditions, k: int = 3, at=None, *, label: str | None = None,
                all_versions: bool = False, include_deprecated: bool = False) -> list:
        """The ``k`` versions closest to ``conditions``, as :meth:`jointdb.store.Repository.nearest`.

        Parameters
        ----------
        joint_type, conditions, k, at, label, all_versions, include_deprecated
            As :meth:`jointdb.store.Repository.nearest`.

        Returns
        -------
        list of Match
        """
        from jointdb.store._query import OutsideCatalogueWarning
        from jointdb.store._types import Match, as_conditions

        cond = as_conditions(conditions).to_dict()
        body = {"joint_type": joint_type, "conditions": cond, "k": int(k), **({"at": str(at)} if at else {}),
                **({"label": label} if label else {}), "all_versions": bool(all_versions),
                "include_deprecated": bool(include_deprecated)}
        out = self._call("POST", "/query/nearest", json=body)
        for w in out["warnings"]:
            warnings.warn(w, OutsideCatalogueWarning, stacklevel=2)
        return [Match(version_from_json(m["joint"]), m["distance"], m["per_condition"], m["extrapolating"],
                      tuple(m["outside_range"])) for m in out["matches"]]

    def interpolate(self, matches, conditions=None, *, method: str = "axes"):
        """As :meth:`jointdb.store.Repository.interpolate`; the server interpolates with ``method="axes"``.

        Parameters
        ----------
        matches, conditions
            As :meth:`jointdb.store.Repository.interpolate`.
        method
            ``"axes"`` only.

        Returns
        -------
        InterpolatedJoint
        """
        from jointdb.store._types import InterpolatedJoint, as_conditions

        if not matches:
            raise InputError("nothing to interpolate: no matches")
        if method != "axes":
            raise InputError(f"the server interpolates with method 'axes' only, not {method!r}")
        cond = as_conditions(conditions)
        body = {"joint_type": matches[0].version.joint_type, "conditions": cond.to_dict(), "k": len(matches)}
        out = self._call("POST", "/query/interpolate", json=body)
        return InterpolatedJoint(frf_from_json(out["frf"]), out["joint_type"], cond,
                                 tuple((n["name"], n["version"], n["weight"]) for n in out["neighbours"]),
                                 out["label"], tuple((n["name"], n["version"], n["lines"])
                                                     for n in out.get("passivity_moved", ())))

    # ---------------------------------------------------------------- writes
    def catalogue(self, name, joint_type, frf, conditions, model_kind, provenance=None, quality=None, parent=None,
                  *, raw_frfs=None, author=None, label=None, force=False, allow_identical=False):
        """Catalogue on the server (the token's owner is the author; raw measurements stay local).

        Parameters
        ----------
        name, joint_type, frf, conditions, model_kind, provenance, quality, parent, label, force, allow_identical
            As :meth:`jointdb.store.Repository.catalogue`.
        raw_frfs, author
            Accepted for the protocol's sake and not sent: the server records the token's owner
            and keeps no raw measurements from a client.

        Returns
        -------
        JointVersion
        """
        return self.catalogue_outcome(name, joint_type, frf, conditions, model_kind, provenance, quality, parent,
                                      raw_frfs=raw_frfs, author=author, label=label, force=force,
                                      allow_identical=allow_identical)[0]

    def catalogue_outcome(self, name, joint_type, frf, conditions, model_kind, provenance=None, quality=None,
                          parent=None, *, raw_frfs=None, author=None, label=None, force=False,
                          allow_identical=False) -> "Catalogued":
        """:meth:`catalogue`, returning ``(version, created)`` (``created`` False: identical to the
        latest version, nothing written). The request carries an ``Idempotency-Key`` and is
        retried with the same key after a connection error or a 503, so a retry never makes a
        second version.

        Parameters
        ----------
        name, joint_type, frf, conditions, model_kind, provenance, quality, parent, raw_frfs, author, label, force, allow_identical
            As :meth:`catalogue`.

        Returns
        -------
        Catalogued
        """
        from jointdb.store._reports import Catalogued
        from jointdb.store._types import as_conditions, as_provenance

        prov = as_provenance(provenance)
        body = {"name": name, "joint_type": joint_type, "model_kind": model_kind, "frf": frf_json(frf),
                "conditions": as_conditions(conditions).to_dict(), "quality": dict(quality or {}),
                "method": prov.method, "input_files": dict(prov.input_files), "parameters": dict(prov.parameters),
                **({"parent": parent} if parent is not None else {}), **({"label": label} if label else {}),
                **({"force": True} if force else {}), **({"allow_identical": True} if allow_identical else {})}
        body["frf"].pop("units", None)
        data, status = self._post_idempotent("/catalogue", body)
        return Catalogued(version_from_json(data), status == 201)

    def _post_idempotent(self, path: str, body: dict) -> tuple[Any, int]:
        """POST ``body`` with a fresh ``Idempotency-Key``; after a connection error or a 503 the
        same request (same key) is sent again, up to :data:`RETRIES` times with a growing pause."""
        import time
        import uuid

        headers = {"Idempotency-Key": uuid.uuid4().hex}
        delay = 0.2
        for attempt in range(RETRIES + 1):
            try:
                r = self._http.post(path, json=body, headers=headers)
            except self._httpx.TransportError as exc:
                if attempt == RETRIES:
                    raise InputError(f"cannot reach the jointdb server {self.url}: {type(exc).__name__} "
                                     f"(after {RETRIES} retries)") from None
            else:
                if r.status_code != 503 or attempt == RETRIES:
                    return self._answer(r), r.status_code
            time.sleep(delay)
            delay = min(delay * 2, 5.0)
        raise AssertionError("unreachable")  # pragma: no cover

    def label(self, name: str, version: int, label: str, author: str | None = None):
        """Point ``label`` at a version.

        Parameters
        ----------
        name, version
            The joint and version.
        label
            The label.
        author
            Not sent: the server records the token's owner.

        Returns
        -------
        JointVersion
        """
        return version_from_json(self._call("POST", f"/joints/{self._name(name)}/labels",
                                            json={"version": int(version), "label": label}))

    def deprecate(self, name: str, version: int | None = None, reason: str = "", author: str | None = None,
                  undo: bool = False) -> list:
        """Deprecate a version (or, with ``version=None``, the whole joint), or undo that.

        Parameters
        ----------
        name
            The joint.
        version
            The version (None: the whole joint, including versions catalogued later).
        reason
            Why, recorded in the audit log.
        author
            Not sent: the server records the token's owner.
        undo
            Make the version(s) active again.

        Returns
        -------
        list of JointVersion
            The joint's history afterwards.
        """
        body = {"reason": reason, "undo": undo, **({"version": int(version)} if version is not None else {})}
        return [version_from_json(v) for v in self._call("POST", f"/joints/{self._name(name)}/deprecate",
                                                         json=body)["items"]]

def version_from_json(d: dict):
    """A :class:`jointdb.store.JointVersion` from the API's JSON form of a version.

    Parameters
    ----------
    d
        The decoded JSON object of a version (``GET /api/v1/joints/{name}``).

    Returns
    -------
    JointVersion
    """
    from jointdb.store._types import Conditions, JointVersion, Provenance

    p = d["provenance"]
    return JointVersion(
        name=d["name"], joint_type=d["joint_type"], version=d["version"], uuid=d["uuid"],
        created_at=datetime.fromisoformat(d["created_at"]), conditions=Conditions.from_dict(d["conditions"]),
        model_kind=d["model_kind"], dofs=tuple(d["dofs"]), quantity=d["quantity"], n_freq=d["n_freq"],
        freq_min_hz=d["freq_min_hz"], freq_max_hz=d["freq_max_hz"], blob_sha256=d["blob_sha256"],
        provenance=Provenance(method=p["method"], parameters=p["parameters"], input_files=p["input_files"],
                              software_version=p["software_version"], author=p["author"]),
        parent_version=d["parent_version"], quality=d["quality"], raw_blobs={k: "" for k in d["raw_measurements"]},
        record_sha256=d["record_sha256"], state=d["state"], labels=tuple(d["labels"]))
