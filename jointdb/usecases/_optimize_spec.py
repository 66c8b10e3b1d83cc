"""Reading an optimize spec into an :class:`OptimizeProblem`: the template stack, the spindle and the
holders from the parts catalogue, and the cut.

A spec is a file (its ``stack`` a file beside it, or inline) or a document sent to the service (the
stack inline, parts by ``{"part": "name@version"}``; ``allow_files=False`` refuses anything that would
read a file on the server). Catalogue choices are resolved once, here, and *pinned*: a family or a
label becomes the ``name@version`` of each holder it selected, a machine name its spindle's
``name@version`` (:attr:`OptimizeProblem.pinned`), so that Dask workers loading the problem again see
exactly the parts this process saw even if a label moves meanwhile.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jointdb.errors import InputError, NotFoundError


@dataclass(frozen=True)
class HolderOption:
    """One allowed holder: its name in the ranking (``name@version`` for a catalogued part), the holder
    object as in a stack file (None: the template's) and the taper of its holder–spindle query [m]
    (None: the template's)."""

    name: str
    holder: Any = None
    taper_diameter_m: float | None = None
    part: str | None = None


@dataclass(frozen=True, eq=False)
class OptimizeProblem:
    """The parsed spec: the file model, the template stack, the cut and the resolved holders.

    ``pinned`` is the spec document with every catalogue choice pinned to ``name@version`` (JSON text)
    and ``base`` the folder a file-named stack is read from: what a Dask worker loads the problem from.
    ``notes`` says which holders a family or label selected and which were left out (and why).
    """

    spec: Any  # jointdb.schemas.optimize.OptimizeSpecFile
    template: Any  # jointdb.stack.StackSpec
    cut: Any  # jointdb.stability.MillingCut
    source: Path | None = None  # the spec file, when read from one
    holders: tuple = ()
    pinned: str = ""
    base: str | None = None
    notes: tuple = ()

    def holder(self, name: str) -> HolderOption:
        """The allowed holder called ``name`` (KeyError: none)."""
        for h in self.holders:
            if h.name == name:
                return h
        raise KeyError(name)


def _validate(doc: Any, where: str):
    from jointdb.schemas import parse

    if not isinstance(doc, dict):
        raise InputError(f"{where}: an optimize spec is a JSON object (format jointdb-optimize/1)")
    return parse("optimize", doc, where)


def load_problem(path: Path | str, repo=None) -> OptimizeProblem:
    """Read an optimize spec file and its template stack (InputError naming the field).

    Parameters
    ----------
    path
        The optimize spec JSON file (:class:`jointdb.schemas.optimize.OptimizeSpecFile`); a stack file it
        names is relative to it.
    repo
        The joint store parts are read from (a spindle part, holders by part or family, parts the stack
        names); None: the default database, opened only when the spec names a part.

    Returns
    -------
    OptimizeProblem
        The validated spec, the template :class:`jointdb.stack.StackSpec`, the
        :class:`jointdb.stability.MillingCut` (flutes, cutting coefficients in N/m², radial
        immersion, down or up milling), the allowed holders and the spec file's resolved path.

    Raises
    ------
    InputError
        Naming the file and the field.
    NotFoundError
        A missing spec or stack file (or a file the stack names), an unknown part or label, a family
        without holders.
    """
    from jointdb.schemas._jsonfile import read_json_file

    p = Path(path)
    doc = read_json_file(p, "optimize spec")
    problem = problem_from_document(doc, repo, base=p.parent, where=p.name)
    from dataclasses import replace

    return replace(problem, source=p.resolve())


def problem_from_document(doc: Any, repo=None, *, base: Path | str | None = None, where: str = "spec",
                          allow_files: bool = True) -> OptimizeProblem:
    """An :class:`OptimizeProblem` from a parsed spec document (a file's, or a service job's body).

    Parameters
    ----------
    doc
        The parsed ``jointdb-optimize/1`` document.
    repo
        The joint store parts are read from (None: the default database, opened only when needed).
    base
        Folder a file-named stack is read from (None: a stack file is refused).
    where
        How errors name the document.
    allow_files
        False (the service): refuse a stack file, a spindle model file or a measured spindle file; parts
        come from the catalogue and everything else inline.

    Returns
    -------
    OptimizeProblem

    Raises
    ------
    InputError, NotFoundError
        As :func:`load_problem`.
    """
    from jointdb.stability import MillingCut
    from jointdb.usecases._parts import _open

    spec = _validate(doc, where)
    needs_store = (spec.machine.spindle or spec.machine.name or any(h.part or h.family for h in spec.holders)
                   or (isinstance(spec.stack, dict) and ('"part"' in json.dumps(spec.stack) or "@" in json.dumps(
                       spec.stack.get("interfaces")))))
    handle, owned = _open(repo) if needs_store else (repo, False)
    try:
        template = _template(spec, handle, base, allow_files)
        spindle_part = next((p for p in template.parts if p.get("slot") == "spindle"), None)
        holders, notes = _holders(spec, template, handle, spindle_part)
        pinned_joints = _pinned_joints(template, handle)
    except (InputError, NotFoundError) as exc:  # named after the document, as the schema's errors are
        text = str(exc)
        raise type(exc)(text if text.startswith(f"{where}: ") else f"{where}: {text}") from None
    finally:
        if owned:
            handle.close()
    kt, kr = spec.cut.coefficients
    cut = MillingCut(spec.tool.flutes, kt, kr, spec.cut.radial_immersion, spec.cut.down_milling)
    pinned = spec.model_dump(mode="json", exclude_none=True)
    pinned["holders"] = [_pinned_holder(h) for h in holders] if spec.holders else []
    if isinstance(pinned["stack"], dict):  # joints pinned by label: to the version the label named now
        pinned["stack"]["interfaces"] = {**pinned["stack"].get("interfaces", {}), **pinned_joints}
    if isinstance(pinned["stack"], dict):  # the stack's own part references, pinned to the versions read
        for used in template.parts:
            if isinstance(pinned["stack"].get(used["slot"]), dict) and "part" in pinned["stack"][used["slot"]]:
                pinned["stack"][used["slot"]] = {"part": used["part"]}
    if spindle_part is not None and (spec.machine.spindle or spec.machine.name):
        pinned["machine"].pop("name", None)
        pinned["machine"]["spindle"] = spindle_part["part"]
    return OptimizeProblem(spec, template, cut, None, tuple(holders), json.dumps(pinned, sort_keys=True),
                           None if base is None else str(Path(base).resolve()), tuple(notes))


def _pinned_joints(template, handle) -> dict:
    """``interface -> {"joint": "name@version"}`` for the interfaces that pin a catalogued joint by label."""
    out = {}
    for name, choice in template.interfaces.items():
        if choice.kind == "catalogued" and not isinstance(choice.version, int):
            jv = handle.get(choice.name, label=str(choice.version))
            out[name] = {"joint": f"{jv.name}@{jv.version}"}
    return out


def _pinned_holder(h: HolderOption) -> dict:
    out: dict = {"part": h.part} if h.part else {"name": h.name, **({"holder": h.holder} if h.holder else {})}
    if h.taper_diameter_m is not None:
        out["taper_diameter_m"] = h.taper_diameter_m
    return out


def _template(spec, handle, base, allow_files: bool):
    """The template stack, with the machine's spindle part when the spec names one."""
    from jointdb.stack import stack_to_dict
    from jointdb.usecases._files import load_stack
    from jointdb.usecases._parts import stack_from_document

    if isinstance(spec.stack, str):
        if not allow_files or base is None:
            raise InputError("stack: send the stack document inline (parts as {\"part\": \"name@version\"}); "
                             "the service reads no files")
        tpl = load_stack(Path(base) / spec.stack, handle)
    else:
        tpl = stack_from_document(spec.stack, handle)
        if not allow_files:
            _no_files(tpl)
    ref = _spindle_ref(spec.machine, handle)
    if ref is None:
        return tpl
    doc = stack_to_dict(tpl)
    doc["spindle"] = {"part": ref}
    with_spindle = stack_from_document(doc, handle)
    others = tuple(p for p in tpl.parts if p.get("slot") != "spindle")
    return with_spindle.replace(parts=others + tuple(with_spindle.parts))


def _no_files(tpl) -> None:
    from jointdb.stack import MeasuredSpindle, ModelledSpindle

    sp = tpl.spindle
    if (isinstance(sp, MeasuredSpindle) and sp.frf is None) or (isinstance(sp, ModelledSpindle)
                                                                 and isinstance(sp.model, str)):
        raise InputError("stack.spindle: refers to a file; send the spindle model inline or name a catalogued "
                         "part (machine.spindle, or {\"part\": \"name@version\"}; the server reads no files)")


def _spindle_ref(machine, handle) -> str | None:
    """``name@version`` of the spindle the spec's machine names (a part reference, or its machine's one spindle)."""
    if machine.spindle is not None:
        part = handle.resolve_part(machine.spindle)
    elif machine.name is not None:
        found = handle.list_parts("spindle", machine=machine.name)
        if len(found) != 1:
            names = ", ".join(p.name for p in found)[:200]
            raise (NotFoundError(f"machine.name: no catalogued spindle of machine {machine.name!r}") if not found else
                   InputError(f"machine.name: machine {machine.name!r} has {len(found)} spindles ({names}); "
                              "name one as machine.spindle"))
        part = found[0]
    else:
        return None
    if part.kind != "spindle":
        raise InputError(f"machine.spindle: {part.ref} is a {part.kind}, not a spindle")
    return part.ref


def _shank_diameter(template) -> float:
    geom = dict((getattr(template.interfaces.get("tool-holder"), "conditions", None) or {}).get("geometry") or {})
    return float(geom.get("shank_diameter_m") or template.tool.segments[-1].diameter)


def _fits(part, shank_m: float, spindle_taper: str | None) -> str | None:
    """Why a catalogued holder does not fit the tool's shank or the spindle's taper (None: it fits)."""
    if part.kind != "holder":
        return f"{part.ref} is a {part.kind}, not a holder"
    bore = part.attributes.get("bore_mm")
    if bore is not None and not math.isclose(bore * 1e-3, shank_m, rel_tol=1e-6):
        return f"{part.ref}: bore {bore:g} mm does not take the {shank_m * 1e3:g} mm shank"
    taper = part.attributes.get("taper")
    if spindle_taper and taper and taper != spindle_taper:
        return f"{part.ref}: taper {taper} does not fit the spindle's {spindle_taper}"
    return None


def _holders(spec, template, handle, spindle_part) -> tuple[list[HolderOption], list[str]]:
    """The allowed holders (inline, catalogued parts, families), those of a family that do not fit left out."""
    from jointdb.schemas.optimize import MAX_HOLDERS

    if not spec.holders:
        return [HolderOption("template")], []
    spindle_taper = None
    if spindle_part is not None:
        spindle_taper = handle.resolve_part(spindle_part["part"]).attributes.get("taper")
    shank = _shank_diameter(template)
    out, notes = [], []
    for i, choice in enumerate(spec.holders):
        if choice.name is not None:
            if choice.holder is not None:  # checked now (a hostile or wrong holder is the spec's error, not a job's)
                from jointdb.stack._stackfile import substructure_from_dict

                substructure_from_dict("holder", choice.holder, f"holders[{i}].holder")
            out.append(HolderOption(choice.name, choice.holder, choice.taper_diameter_m))
            continue
        if choice.part is not None:
            part = handle.resolve_part(choice.part)
            why = _fits(part, shank, spindle_taper)
            if why:
                raise InputError(f"holders[{i}].part: {why}")
            out.append(HolderOption(part.ref, dict(part.payload), choice.taper_diameter_m, part.ref))
            continue
        picked = []
        for latest in handle.list_parts("holder", family=choice.family):
            part = latest if choice.label is None else _labelled(handle, latest.name, choice.label)
            if part is None:
                continue
            why = _fits(part, shank, spindle_taper)
            if why:
                notes.append(f"holders[{i}] (family {choice.family}): left out {why}")
                continue
            picked.append(HolderOption(part.ref, dict(part.payload), choice.taper_diameter_m, part.ref))
        if not picked:
            with_label = f" labelled {choice.label!r}" if choice.label else ""
            raise NotFoundError(f"holders[{i}]: no catalogued holder of family {choice.family!r}{with_label} fits "
                                f"the {shank * 1e3:g} mm shank" + (f" and the {spindle_taper} spindle" if spindle_taper else ""))
        notes.append(f"holders[{i}]: family {choice.family}{' @' + choice.label if choice.label else ''}: "
                     f"{', '.join(h.name for h in picked)}")
        out += picked
    names = [h.name for h in out]
    if len(set(names)) != len(names):
        raise InputError(f"holders: a holder is allowed twice ({', '.join(sorted({n for n in names if names.count(n) > 1}))[:200]})")
    if len(out) > MAX_HOLDERS:
        raise InputError(f"holders: {len(out)} holders selected; the limit is {MAX_HOLDERS} (narrow the families)")
    return out, notes


def _labelled(handle, name: str, label: str):
    """The version of part ``name`` that ``label`` points at (None: the label is not on this part)."""
    try:
        return handle.get_part(name, label=label)
    except NotFoundError:
        return None
