"""``python -m jointdb`` runs the CLI."""

from jointdb.cli import main

main()
