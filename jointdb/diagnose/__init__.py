"""(module under construction)."""
