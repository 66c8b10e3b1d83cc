"""Finite-element beam models that give receptances (with rotations) at any node.

A model is a stepped shaft along z (:class:`Segment` s of (hollow) circular
section), named points that map model positions to measurement node numbers,
and a tuple of independent, composable *ingredients* — :class:`Clamp`,
:class:`Support`, :class:`PointMass`, :class:`ModalDamping`,
:class:`RayleighDamping`, :class:`HystereticDamping` — each applied to the
assembled matrices by its own ``apply(matrices, mesh)`` step. Two ingredients
describe interfaces inside the shaft: a :class:`Joint` splits the beam at a
position into two sides tied by springs (a tool–holder face, a flange), and an
:class:`Insertion` puts a concentric part inside the host over an overlap (a
tool shank in the holder bore), tied rigidly or by a :class:`Contact` layer.

DOFs (api-contracts.md): planar models have ``x`` and ``ry`` (= +dx/dz) per
node; 3-D frames have ``x y z rx ry rz`` with z axial, ``rz`` torsion,
``rx = −dy/dz``. Timoshenko elements (Cowper's shear coefficient for solid and
hollow circles, consistent translational and rotary inertia) or
Euler–Bernoulli (no shear, no rotary inertia).

Example
-------
>>> from jointdb.fe import BeamModel, Segment, NamedPoint, Clamp, ModalDamping
>>> model = BeamModel(
...     segments=(Segment(0.08, 0.012, material="carbide"),),
...     points=(NamedPoint("tip", 0.0, node=1),),
...     ingredients=(Clamp(0.08), ModalDamping(0.01)),
... )
>>> frf = model.frf([100.0, 200.0], points=["tip"])          # FRF, outputs 1x 1ry
>>> modes = model.modes(3)                                     # Modes.freq_hz

Deviations from api-contracts.md (additive only): ``Clamp(position,
directions=None)`` can fix chosen directions (pinned support);
``PointMass(..., polar_inertia=0.0)`` for 3-D torsion; ``FEMatrices`` also
carries ``fixed`` (bool mask of constrained DOFs); ``Modes`` carries
``n_rigid``; ``BeamModel`` has ``name``, ``point(name)`` and ``mesh()``.
"""

from jointdb.fe._elements import bar_matrices, bending_matrices, section_properties, shear_coefficient
from jointdb.fe._ingredients import (
    Clamp,
    HystereticDamping,
    Ingredient,
    ModalDamping,
    PointMass,
    RayleighDamping,
    Support,
)
from jointdb.fe._joints import Contact, Insertion, Joint
from jointdb.fe._materials import MATERIALS, Material, get_material
from jointdb.fe._model import BeamModel, FEMatrices, Mesh, Modes, NamedPoint, Segment
from jointdb.fe._modelfile import FORMAT, load_model, model_from_dict, model_to_dict
from jointdb.fe._synthesis import frf_direct, frf_modal, natural_modes, rigid_body_count

__all__ = [
    "Material",
    "MATERIALS",
    "get_material",
    "Segment",
    "NamedPoint",
    "Ingredient",
    "Clamp",
    "Support",
    "PointMass",
    "ModalDamping",
    "RayleighDamping",
    "HystereticDamping",
    "Joint",
    "Insertion",
    "Contact",
    "BeamModel",
    "FEMatrices",
    "Mesh",
    "Modes",
    "load_model",
    "model_from_dict",
    "model_to_dict",
    "FORMAT",
    "natural_modes",
    "frf_direct",
    "frf_modal",
    "rigid_body_count",
    "section_properties",
    "shear_coefficient",
    "bending_matrices",
    "bar_matrices",
]
