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

DOFs: planar models have ``x`` and ``ry`` (= +dx/dz) per node; 3-D frames have
``x y z rx ry rz`` with z axial, ``rz`` torsion, ``rx = −dy/dz``. Timoshenko
elements (Cowper's shear coefficient for solid and hollow circles, consistent
translational and rotary inertia) or Euler–Bernoulli (no shear, no rotary inertia).

Models
------
   BeamModel           -- a stepped shaft with named points and ingredients; ``.frf``, ``.modes``
   Segment             -- a uniform (hollow) circular shaft segment
   NamedPoint          -- a named position mapped to a measurement node number
   Material            -- an isotropic linear-elastic material
   MATERIALS           -- the built-in materials by name
   get_material        -- look a material up by name

Ingredients
-----------
   Ingredient          -- base class: ``stage`` orders them, ``positions`` feed the mesh
   Clamp               -- fix DOFs at one position
   Support             -- springs and viscous dampers to ground
   PointMass           -- a lumped mass with rotary inertia
   ModalDamping        -- modal viscous damping ratios ζ
   RayleighDamping     -- proportional damping ``C = α M + β K``
   HystereticDamping   -- structural damping ``K (1 + iη)``
   Joint               -- a compliant joint splitting the beam
   Insertion           -- a concentric part inside the host beam
   Contact             -- a distributed contact layer of an insertion

Model files
-----------
   load_model          -- read a JSON model file
   model_from_dict     -- a model from its parsed JSON description
   model_to_dict       -- the JSON description of a model
   FORMAT              -- the model file format tag

Solution
--------
   natural_modes       -- natural frequencies [Hz] and mass-normalised shapes
   natural_frequencies -- the natural frequencies alone (cheaper)
   frf_direct          -- receptances by direct solution, batched over frequency
   frf_modal           -- receptances by modal superposition with residual compensation
   rigid_body_count    -- number of rigid-body modes left after constraints
   FEMatrices          -- assembled matrices over all mesh DOFs
   Mesh                -- nodes, elements and DOF numbering
   Modes               -- natural frequencies and mode shapes

Elements
--------
   section_properties  -- area, second and polar moment of a (hollow) circle
   shear_coefficient   -- Timoshenko shear coefficient κ
   bending_matrices    -- stiffness and consistent mass of planar beam elements
   bar_matrices        -- axial or torsion bar elements

Beyond the plain beam: ``Clamp(position, directions=None)`` can fix chosen directions
(pinned support); ``PointMass(..., polar_inertia=0.0)`` for 3-D torsion; ``FEMatrices``
also carries ``fixed`` (bool mask of constrained DOFs); ``Modes`` carries ``n_rigid``;
``BeamModel`` has ``name``, ``point(name)`` and ``mesh()``.

Examples
--------
A clamped 80 mm carbide rod of 12 mm diameter. Its first bending mode lies about 1 % below
the Euler–Bernoulli value ``(1.8751² / 2π) √(EI / ρAL⁴)`` (shear and rotary inertia, L/d = 6.7),
and its tip receptance at 20 Hz is the static bending compliance ``L³ / 3EI`` plus about 1 %
of shear deflection:

>>> import numpy as np
>>> from jointdb.fe import BeamModel, Segment, NamedPoint, Clamp, ModalDamping, get_material
>>> model = BeamModel(
...     segments=(Segment(0.08, 0.012, material="carbide"),),
...     points=(NamedPoint("tip", 0.0, node=1),),
...     ingredients=(Clamp(0.08), ModalDamping(0.01)),
... )
>>> mat, L, d = get_material("carbide"), 0.08, 0.012
>>> EI, rhoA = mat.E * np.pi * d**4 / 64, mat.rho * np.pi * d**2 / 4
>>> f_eb = 1.8751**2 / (2 * np.pi) * np.sqrt(EI / (rhoA * L**4))
>>> round(float(model.modes(3).freq_hz[0] / f_eb), 2)
0.99
>>> frf = model.frf([20.0], points=["tip"])          # outputs 1x, 1ry; receptance in m/N, rad/N
>>> [str(dof) for dof in frf.outputs]
['1x', '1ry']
>>> round(float(frf.entry("1x", "1x")[0].real / (L**3 / (3 * EI))), 2)
1.01
"""

from jointdb.fe import _ingredients
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
from jointdb.fe._rigid import rigid_body_count
from jointdb.fe._synthesis import frf_direct, frf_modal, natural_frequencies, natural_modes

__all__ = [
    "Material",
    "MATERIALS",
    "get_material",
    "Segment",
    "NamedPoint",
]
__all__ += _ingredients.__all__  # Ingredient and its kinds
__all__ += [
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
    "natural_frequencies",
    "natural_modes",
    "frf_direct",
    "frf_modal",
    "rigid_body_count",
    "section_properties",
    "shear_coefficient",
    "bending_matrices",
    "bar_matrices",
]
