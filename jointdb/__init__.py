"""jointdb: identify, catalogue and reuse machine-tool joint dynamics.

The public namespace is curated: the FRF container and the error hierarchy live
here; numerics live in :mod:`jointdb.fe`, :mod:`jointdb.coupling`,
:mod:`jointdb.modal`, :mod:`jointdb.stack`, :mod:`jointdb.stability` and
:mod:`jointdb.diagnose`; storage in :mod:`jointdb.store`; files in
:mod:`jointdb.io`.

The FRF names (``FRF``, ``Dof``, ``Quantity``, ``dofs``, ``DIRECTIONS``) are
loaded on first use, so that ``import jointdb`` (and the command line's
``--help``) does not import numpy.
"""

from jointdb.errors import (
    ConflictError,
    InputError,
    IntegrityError,
    JointdbError,
    NotFoundError,
    NumericalError,
)

__version__ = "0.1.0"

__all__ = [
    "DIRECTIONS",
    "FRF",
    "Dof",
    "Quantity",
    "dofs",
    "JointdbError",
    "InputError",
    "NotFoundError",
    "ConflictError",
    "IntegrityError",
    "NumericalError",
    "__version__",
]

_FROM_FRF = ("DIRECTIONS", "FRF", "Dof", "Quantity", "dofs")


def __getattr__(name: str):
    if name in _FROM_FRF:
        from jointdb import frf

        value = getattr(frf, name)
        globals()[name] = value  # later look-ups do not come here again
        return value
    raise AttributeError(f"module 'jointdb' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
