"""The library of candidate physics: what a model may have left out.

Each candidate is a small object with a ``name``, the ``family`` of physics it
belongs to, a plain-language ``explanation``, bounded :class:`Param` s with
physically sensible starting values, and

- ``apply(model, values, level) -> model`` adding jointdb.fe ingredients
  (a support, a point mass, a damping law, a theory, a diameter), and/or
- ``chain(freq, values, level) -> factor`` multiplying the FRF (measurement
  chain: calibration gain, time delay).

Adding a new physics is one small module in this package: define a
:class:`Candidate` subclass and a factory ``f(context) -> iterable of
candidates`` decorated with :func:`register`, then import the module below.
"""

from __future__ import annotations

from jointdb.diagnose.physics._candidate import (
    REGISTRY,
    Candidate,
    Combination,
    Context,
    Param,
    candidates_for,
    register,
)

__all__ = ["Param", "Context", "Candidate", "Combination", "register", "candidates_for", "REGISTRY"]

# the library (import order = report order for ties)
from jointdb.diagnose.physics import (  # noqa: E402,F401
    amplitude,
    bed,
    chain,
    damping,
    diameter,
    interface,
    joint,
    microslip,
    sensor,
    suspension,
    theory,
)
