"""CLI for signing keys: ``jointdb keys create`` (registered by :mod:`jointdb.cli._store`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointdb.cli._output import emit


def register(app: typer.Typer) -> None:
    """Add ``keys ...`` to the app."""
    keys = typer.Typer(help="Ed25519 keys to sign exported bundles and verify imported ones.", no_args_is_help=True)
    app.add_typer(keys, name="keys")

    @keys.command("create")
    def create(
        out: Annotated[Path, typer.Argument(help="Private key file to write; the public key goes to OUT.pub.")],
        as_json: Annotated[bool, typer.Option("--json", help="Write JSON to stdout instead of a table.")] = False,
    ) -> None:
        """Create a key pair: keep OUT private (mode 0600), give OUT.pub to those who import your bundles.

        Example: jointdb keys create lab-key ; jointdb joints export lab.h5 --sign lab-key
        """
        from jointdb.store._signing import create_key_pair, fingerprint, load_public_key, public_raw

        private, public = create_key_pair(out)
        emit({"private_key": str(private), "public_key": str(public),
              "fingerprint": fingerprint(public_raw(load_public_key(public)))}, as_json=as_json)
