"""Validation of a model's fields: the error naming the field, and the number check.

Shared by every part of a model (segments, points, ingredients, interfaces), so it sits
below all of them.
"""

from __future__ import annotations

import math

import numpy as np

from jointdb.errors import InputError

__all__ = ["FieldError"]


class FieldError(InputError):
    """An :class:`InputError` about one named field (the model loader adds the path)."""

    def __init__(self, field_name: str, reason: str) -> None:
        self.field = field_name
        self.reason = reason
        super().__init__(f"{field_name}: {reason}")


def _number(obj, name: str, *, minimum: float | None = None, strict: bool = False) -> float:
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise FieldError(name, f"must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise FieldError(name, f"must be finite, got {value!r}")
    if minimum is not None:
        if strict and not value > minimum:
            raise FieldError(name, f"must be > {minimum:g}, got {value:g}")
        if not strict and value < minimum:
            raise FieldError(name, f"must be >= {minimum:g}, got {value:g}")
    object.__setattr__(obj, name, value)
    return value
