"""The bundled example data, copied out of the installed package (``jointdb examples DIR``).

The package ships its example files as package data under ``jointdb/data/``
(they are also reachable in a clone through ``fixtures/bundled``). They are
laid out for a user as::

    DIR/models/      beam model files (JSON, SI): the end mill in its holder, and the
                     test tools and holders the campaigns use
    DIR/campaigns/   six tool-holder test campaigns (jointdb-campaign/1: models,
                     measured assembly FRFs as UFF58, truth.json with the joint the
                     synthetic measurement was made with)
    DIR/stacks/      a tool / holder / spindle stack file (jointdb-stack/1) that asks
                     the catalogue for its tool-holder joint

Campaigns refer to their models as ``../../models/<file>``, so the layout is kept.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import ExitStack
from importlib import resources
from pathlib import Path

from jointdb.errors import InputError

__all__ = ["copy_examples", "EXAMPLE_LAYOUT"]

#: (source under jointdb/data, target under DIR); a source ending in "/" is a directory.
EXAMPLE_LAYOUT: tuple[tuple[str, str], ...] = (
    ("models/", "models"),
    ("catalogue/models/", "models"),
    ("catalogue/campaigns/", "campaigns"),
    ("catalogue/demo-stack.json", "stacks/demo-stack.json"),
)


def copy_examples(target: str | os.PathLike) -> list[Path]:
    """Copy the bundled models, campaigns and stacks into ``target`` (a new or empty directory).

    All files are copied into a temporary sibling directory first, which is then
    renamed into place: ``target`` gets everything or nothing.

    Returns
    -------
    list of Path
        The files written, relative to ``target``, sorted.

    Raises
    ------
    InputError
        ``target`` exists and is not an empty directory, its parent directory does
        not exist, or the package data is missing (a broken installation).
    """
    dest = Path(target)
    if dest.exists() and (not dest.is_dir() or any(dest.iterdir())):
        raise InputError(f"{dest} already exists and is not an empty directory; give a new directory")
    parent = dest.absolute().parent
    if not parent.is_dir():
        raise InputError(f"cannot write {dest}: directory {parent} does not exist")
    with ExitStack() as stack:
        ref = resources.files("jointdb").joinpath("data")
        if not ref.is_dir():
            raise InputError("the bundled example data jointdb/data is missing from the installed package")
        data = Path(stack.enter_context(resources.as_file(ref)))
        tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=parent))
        try:
            umask = os.umask(0)
            os.umask(umask)
            tmp.chmod(0o777 & ~umask)  # mkdtemp makes it 0700; DIR gets the usual mode
            for src, dst in EXAMPLE_LAYOUT:
                s = data / src
                if src.endswith("/"):
                    if not s.is_dir():
                        raise InputError(f"the bundled example data jointdb/data/{src} is missing")
                    shutil.copytree(s, tmp / dst, dirs_exist_ok=True,
                                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
                else:
                    if not s.is_file():
                        raise InputError(f"the bundled example file jointdb/data/{src} is missing")
                    (tmp / dst).parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(s, tmp / dst)
            written = sorted(p.relative_to(tmp) for p in tmp.rglob("*") if p.is_file())
            if dest.exists():
                dest.rmdir()  # empty (checked above)
            os.replace(tmp, dest)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    return written
