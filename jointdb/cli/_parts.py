"""CLI: ``jointdb parts add | list | show | label`` — spindles, holders and tools as catalogued records.

Thin: :func:`jointdb.usecases.part_from_files` reads the files, the store (a database, or a
server with ``--server``) catalogues and verifies; this module parses options and renders.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from jointdb.cli._output import emit, message
from jointdb.cli._target import BlobsOpt, DbOpt, JsonOpt, open_repo

KINDS_HELP = "spindle, holder or tool"


def _row(p) -> dict[str, Any]:
    a = p.attributes
    return {"name": p.name, "kind": p.kind, "version": p.version, "labels": ",".join(p.labels) or None,
            "machine": a.get("machine"), "family": a.get("family"), "taper": a.get("taper"),
            "bore_mm": a.get("bore_mm"), "measured": p.blob_sha256 is not None, "author": p.author,
            "created_at": p.created_at.isoformat(timespec="seconds")}


def parts_add(
    kind: Annotated[str, typer.Argument(help=f"Part kind: {KINDS_HELP}.")],
    name: Annotated[str, typer.Argument(help="Part name (letters, digits, . _ + -).")],
    model: Annotated[Optional[Path], typer.Option("--model", help="Spindle: beam-model file (JSON).")] = None,
    point: Annotated[Optional[str], typer.Option("--point", help="Spindle: model point the holder sits on.")] = None,
    frf: Annotated[Optional[Path], typer.Option("--frf", help="Spindle: measured nose FRF set (.uff, .h5, .csv) "
                                                "with x, ry (and y, rx) at --node.")] = None,
    node: Annotated[Optional[int], typer.Option("--node", help="Spindle: node of the nose in --frf.")] = None,
    from_stack: Annotated[Optional[Path], typer.Option("--from-stack", help="Take the part of this kind from a "
                                                       "stack file.")] = None,
    file: Annotated[Optional[Path], typer.Option("--file", help="JSON file of the part's stack-file object.")] = None,
    machine: Annotated[Optional[str], typer.Option("--machine", help="Spindle: the machine (required).")] = None,
    family: Annotated[Optional[str], typer.Option("--family", help="Holder family, e.g. ER32, shrink-fit.")] = None,
    taper: Annotated[Optional[str], typer.Option("--taper", help="Holder / spindle taper, e.g. HSK-A63.")] = None,
    bore_mm: Annotated[Optional[float], typer.Option("--bore-mm", help="Holder bore [mm].")] = None,
    description: Annotated[Optional[str], typer.Option("--description", help="Free text.")] = None,
    label: Annotated[Optional[str], typer.Option("--label", help="Point this label at the version.")] = None,
    author: Annotated[Optional[str], typer.Option("--author", help="Author (default $JOINTDB_AUTHOR or "
                                                  "the login).")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Catalogue a spindle, holder or tool as a new immutable part version (identical content: nothing written).

    A stack file may then name it instead of carrying it inline: "holder": {"part": "NAME@VERSION"}
    (or NAME@LABEL); `jointdb predict` resolves it and reports the versions used.

    Example: jointdb parts add holder er32-hsk63 --from-stack fixtures/bundled/catalogue/demo-stack.json --family ER32 --taper HSK-A63 --bore-mm 12
    """
    from jointdb.store._part_records import check_part_kind, check_part_name
    from jointdb.usecases import part_from_files

    check_part_kind(kind)
    check_part_name(name)
    attributes = {k: v for k, v in (("machine", machine), ("family", family), ("taper", taper),
                                    ("bore_mm", bore_mm), ("description", description)) if v is not None}
    part = part_from_files(kind, model=model, point=point, frf=frf, node=node, from_stack=from_stack, file=file)
    with open_repo(db, blobs, create=True) as r:
        before = {p.version for p in _history_or_empty(r, name)}
        pv = r.add_part(name, kind, part.payload, frf=part.frf, attributes=attributes,
                        provenance=part.provenance, author=author, label=label)
    message(f"{'catalogued' if pv.version not in before else 'identical to'} {pv.ref} ({pv.kind})")
    emit(pv.to_dict() if as_json else [_row(pv)], as_json=as_json)


def _history_or_empty(r, name: str) -> list:
    from jointdb.errors import NotFoundError

    try:
        return r.part_history(name)
    except NotFoundError:
        return []


def parts_list(
    kind: Annotated[Optional[str], typer.Option("--kind", help=f"Only parts of this kind ({KINDS_HELP}).")] = None,
    family: Annotated[Optional[str], typer.Option("--family", help="Only holders of this family.")] = None,
    machine: Annotated[Optional[str], typer.Option("--machine", help="Only spindles of this machine.")] = None,
    db: DbOpt = None, as_json: JsonOpt = False,
) -> None:
    """List catalogued parts: the latest version of each, with its attributes.

    Example: jointdb parts list --kind holder
    """
    with open_repo(db) as r:
        items = r.list_parts(kind, family=family, machine=machine)
    if as_json:
        emit([p.to_dict() for p in items], as_json=True)
    else:
        emit([_row(p) for p in items], title="parts")


def parts_show(
    ref: Annotated[str, typer.Argument(help="NAME (all versions), NAME@VERSION or NAME@LABEL.")],
    db: DbOpt = None, as_json: JsonOpt = False,
) -> None:
    """Show a part: every version, or one version's record with its payload (verified on read).

    Example: jointdb parts show er32-hsk63@1 --json
    """
    with open_repo(db) as r:
        versions = [r.resolve_part(ref)] if "@" in ref else r.part_history(ref)
    if as_json:
        emit(versions[0].to_dict() if "@" in ref else [v.to_dict() for v in versions], as_json=True)
    else:
        emit([_row(v) for v in versions], title=f"part {ref}")


def parts_label(
    ref: Annotated[str, typer.Argument(help="NAME@VERSION to label.")],
    label: Annotated[str, typer.Argument(help="Label (e.g. released).")],
    db: DbOpt = None, as_json: JsonOpt = False,
) -> None:
    """Point a label of a part at a version (created or moved; audited).

    Example: jointdb parts label er32-hsk63@1 released
    """
    from jointdb.errors import InputError
    from jointdb.store._part_records import parse_part_ref

    name, version = parse_part_ref(ref)
    if not isinstance(version, int):
        raise InputError(f"{ref!r}: label a version number, NAME@VERSION")
    with open_repo(db) as r:
        pv = r.label_part(name, version, label)
    message(f"{label} -> {pv.ref}")
    emit(pv.to_dict() if as_json else [_row(pv)], as_json=as_json)


def register(app: typer.Typer) -> None:
    """Add ``parts add | list | show | label`` to the app."""
    parts = typer.Typer(help="Catalogued stack parts (spindles, holders, tools): add, list, show, label.",
                        no_args_is_help=True)
    app.add_typer(parts, name="parts")
    parts.command("add")(parts_add)
    parts.command("list")(parts_list)
    parts.command("show")(parts_show)
    parts.command("label")(parts_label)
