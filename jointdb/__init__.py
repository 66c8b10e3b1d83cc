"""jointdb: identify, catalogue and reuse machine-tool joint dynamics.

The root holds the FRF container and the error hierarchy; the rest is in packages, each
with a catalogue of its public names in its docstring:

=========================  =====================================================
:mod:`jointdb.fe`          Timoshenko / Euler–Bernoulli beam models, receptances
:mod:`jointdb.coupling`    receptance coupling (RC) and joint identification (IRC)
:mod:`jointdb.modal`       modal parameter estimation and modal models
:mod:`jointdb.stack`       tool / holder / spindle stacks, tool-tip prediction
:mod:`jointdb.stability`   chatter stability lobes
:mod:`jointdb.diagnose`    why a model and a recording disagree
:mod:`jointdb.store`       the versioned joint catalogue (SQLite / PostgreSQL + HDF5)
:mod:`jointdb.client`      the catalogue behind ``jointdb serve``, over HTTP
:mod:`jointdb.io`          FRF files: UFF58, HDF5, CSV, JSON
:mod:`jointdb.plots`       figures
:mod:`jointdb.campaign`    measurement campaign files, identification runs
:mod:`jointdb.usecases`    the use cases the CLI, the HTTP service and the demo call
:mod:`jointdb.schemas`     one schema per file kind, published as JSON Schema
=========================  =====================================================

FRF container
-------------
   FRF             -- frequency response functions ``(n_freq, n_out, n_in)`` on labelled DOFs
   Dof             -- a node number and a direction (``x y z rx ry rz``)
   dofs            -- parse DOF labels (``"1x"``) into :class:`Dof`
   Quantity        -- receptance, mobility or accelerance
   DIRECTIONS      -- the six direction names

Errors
------
   JointdbError    -- base class of all errors jointdb raises on purpose
   InputError      -- a file, array, option or field that is wrong
   NotFoundError   -- a joint, version, label, blob or file that does not exist
   ConflictError   -- a write that would contradict what is stored
   IntegrityError  -- stored data failed verification
   NumericalError  -- a computation that cannot give a trustworthy answer

``__version__`` is the package version. The FRF names are loaded on first use, so that ``import jointdb`` (and the command
line's ``--help``) does not import numpy.
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
