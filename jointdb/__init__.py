"""jointdb: identify, catalogue and reuse machine-tool joint dynamics.

The public namespace is curated: the FRF container and the error hierarchy live
here; numerics live in :mod:`jointdb.fe`, :mod:`jointdb.coupling`,
:mod:`jointdb.modal`, :mod:`jointdb.stack`, :mod:`jointdb.stability` and
:mod:`jointdb.diagnose`; storage in :mod:`jointdb.store`; files in
:mod:`jointdb.io`.
"""

from jointdb.errors import (
    ConflictError,
    InputError,
    IntegrityError,
    JointdbError,
    NotFoundError,
    NumericalError,
)
from jointdb.frf import DIRECTIONS, FRF, Dof, Quantity, dofs

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
