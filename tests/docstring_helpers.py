"""What the public API is, and what its numpydoc docstrings say (for ``test_docstrings`` and ``test_doctests``).

The public API is, for each package of :data:`PUBLIC_MODULES`, the names in its ``__all__``;
a public callable is such a name bound to a function or a class, and the public methods of
a public class (names without a leading underscore, defined in jointdb).
"""

from __future__ import annotations

import dataclasses
import enum
import importlib
import inspect
import re
from collections.abc import Callable, Iterator

#: the packages (and one module) whose ``__all__`` is the public API, in the manner of ``scipy.signal``
PUBLIC_MODULES = (
    "jointdb",
    "jointdb.coupling",
    "jointdb.fe",
    "jointdb.modal",
    "jointdb.stack",
    "jointdb.stability",
    "jointdb.diagnose",
    "jointdb.store",
    "jointdb.io",
    "jointdb.plots",
    "jointdb.campaign",
    "jointdb.usecases",
    "jointdb.schemas",
    "jointdb.client",
)

_HEADER = re.compile(r"^(\w[\w ]*)\n-{3,}\s*$", re.M)
_PARAM_SECTIONS = ("Parameters", "Other Parameters")


def sections(doc: str | None) -> dict[str, str]:
    """The numpydoc sections of a docstring: ``{"Parameters": body, "Returns": body, ...}``.

    A section is a title line underlined by a line of dashes; its body runs to the next title.
    """
    text = inspect.cleandoc(doc or "")
    lines = text.splitlines()
    out: dict[str, list[str]] = {}
    current: str | None = None
    k = 0
    while k < len(lines):
        line = lines[k]
        nxt = lines[k + 1] if k + 1 < len(lines) else ""
        if line.strip() and re.fullmatch(r"-{3,}", nxt.strip()) and len(nxt.strip()) >= len(line.strip()) - 1:
            current = line.strip()
            out[current] = []
            k += 2
            continue
        if current is not None:
            out[current].append(line)
        k += 1
    return {name: "\n".join(body) for name, body in out.items()}


def documented_parameters(doc: str | None, titles: tuple[str, ...] = _PARAM_SECTIONS) -> list[str]:
    """Parameter names listed in the Parameters (and Other Parameters) sections, in order.

    An entry is an unindented line ``name : type`` or ``name`` (``a, b : type`` names two);
    ``*args`` and ``**kwargs`` keep their stars.
    """
    found: list[str] = []
    secs = sections(doc)
    for title in titles:
        for line in secs.get(title, "").splitlines():
            if not line.strip() or line[:1].isspace():
                continue
            head = line.split(" : ", 1)[0].rstrip(" :")
            found.extend(part.strip() for part in head.split(",") if part.strip())
    return found


def signature_parameters(obj: Callable) -> list[str] | None:
    """The names a caller passes to ``obj`` (``*args``/``**kwargs`` with their stars; no ``self``/``cls``).

    None when the signature cannot be read (a builtin without one).
    """
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    names = []
    for p in sig.parameters.values():
        if p.name in ("self", "cls"):
            continue
        if p.kind is p.VAR_POSITIONAL:
            names.append("*" + p.name)
        elif p.kind is p.VAR_KEYWORD:
            names.append("**" + p.name)
        else:
            names.append(p.name)
    return names


def parameter_problems(obj: Callable, doc: str | None = None) -> list[str]:
    """What disagrees between ``obj``'s signature and the Parameters section of ``doc`` (its docstring).

    Every parameter of the signature must be listed; every listed parameter must be in the signature.
    A class (a dataclass above all) may document its constructor's parameters as Attributes too:
    they are its fields.
    """
    doc = inspect.getdoc(obj) if doc is None else doc
    wanted = signature_parameters(obj)
    if wanted is None:
        return []
    listed = documented_parameters(doc)
    fields = documented_parameters(doc, ("Attributes",)) if inspect.isclass(obj) else []
    problems = [f"parameter {name!r} is not documented" for name in wanted if name not in listed + fields]
    problems += [f"documented parameter {name!r} is not in the signature" for name in listed if name not in wanted]
    return problems


def _is_ours(obj: object) -> bool:
    return (getattr(obj, "__module__", "") or "").startswith("jointdb")


def _takes_no_documented_init(cls: type) -> bool:
    """Exceptions, warnings, enums and protocols: their constructor is not part of their documentation."""
    return (issubclass(cls, (BaseException, enum.Enum))
            or getattr(cls, "_is_protocol", False)
            or ("__init__" not in cls.__dict__ and not dataclasses.is_dataclass(cls)
                and "__new__" not in cls.__dict__))


def public_callables() -> Iterator[tuple[str, Callable, Callable]]:
    """``(qualified name, object whose docstring documents it, object whose signature it has)`` for
    every public function, class (its constructor) and public method of a public class."""
    seen: set[int] = set()
    for modname in PUBLIC_MODULES:
        module = importlib.import_module(modname)
        for name in module.__all__:
            obj = getattr(module, name)
            if id(obj) in seen or not _is_ours(obj):
                continue
            if inspect.isfunction(obj):
                seen.add(id(obj))
                yield f"{modname}.{name}", obj, obj
            elif inspect.isclass(obj):
                seen.add(id(obj))
                if not _takes_no_documented_init(obj):
                    yield f"{modname}.{name}", obj, obj
                yield from _methods(f"{modname}.{name}", obj)


def _methods(qualname: str, cls: type) -> Iterator[tuple[str, Callable, Callable]]:
    """The public methods of ``cls``; none for a ``typing.Protocol``, whose methods are documented
    where they are implemented (its docstring names the implementation)."""
    if getattr(cls, "_is_protocol", False):
        return
    own: dict[str, object] = {}
    for base in reversed(cls.__mro__):  # inherited methods too, when jointdb defines them
        if base is not cls and (not _is_ours(base) or getattr(base, "_is_protocol", False)):
            continue
        own.update(vars(base))
    for attr, raw in own.items():
        if attr.startswith("_"):
            continue
        if isinstance(raw, (staticmethod, classmethod)):
            func = getattr(cls, attr)
        elif inspect.isfunction(raw):
            func = raw
        else:
            continue  # properties and constants are attributes, documented with the class
        yield f"{qualname}.{attr}", func, func


def public_modules_with_docstrings() -> Iterator[object]:
    """The public modules and every jointdb module that defines one of their public names."""
    seen: set[str] = set()
    for modname in PUBLIC_MODULES:
        module = importlib.import_module(modname)
        for name in (modname, *(getattr(getattr(module, n), "__module__", None) for n in module.__all__)):
            if isinstance(name, str) and name.startswith("jointdb") and name not in seen:
                seen.add(name)
                yield importlib.import_module(name)
