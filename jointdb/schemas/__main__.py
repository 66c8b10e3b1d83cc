"""``python -m jointdb.schemas DIR``: write the JSON Schemas of the file kinds into DIR (docs/schemas)."""

from __future__ import annotations

import sys
from pathlib import Path

from jointdb.io._atomic import atomic_path
from jointdb.schemas import schema_files


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m jointdb.schemas DIR", file=sys.stderr)
        return 2
    out = Path(argv[0])
    out.mkdir(parents=True, exist_ok=True)
    for name, text in schema_files().items():
        with atomic_path(out / name) as tmp:
            Path(tmp).write_text(text, encoding="utf-8")
        print(out / name)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
