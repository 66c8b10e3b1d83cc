"""Stack description (tool / holder / spindle) and tool-tip FRF prediction.

docs/theory.md §4 (three-component receptance coupling). Pure numerics: no files,
no database. The application layer (:mod:`jointdb.usecases`) reads stack files,
attaches a measured spindle FRF, resolves catalogued joints from the database
and then calls :func:`predict_tool_tip`.

Public API
----------
- :func:`stack_from_dict` (``dict -> StackSpec``, ``InputError`` naming the
  field), :func:`stack_to_dict`; :data:`FORMAT` = ``"jointdb-stack/1"``.
- :class:`StackSpec` (``name, tool, holder, spindle, gauge_length,
  interfaces, frequency``; ``.insertion_length``), :class:`Tool`,
  :class:`ToolSegment` (``fluted`` sections use :data:`KOPS_VO_RATIO` = 0.656
  of the cutter diameter), :class:`Holder`, :class:`HolderSegment`,
  :class:`MeasuredSpindle` (``file, node, frf``), :class:`ModelledSpindle`
  (``model`` = fe model dict or BeamModel, ``point``), :class:`JointChoice`
  (``kind`` rigid / explicit / catalogued / query), :class:`FrequencyGrid`.
- :func:`predict_tool_tip(spec, resolved_joints=None, freq=None) -> Prediction`
  (``tip`` FRF over (1x, 1y), ``rigid``, ``tip_rotation``, ``interfaces``,
  ``notes``, ``.summary()``).
- :func:`stack_parts(spec, freq)` — the parts' free receptances;
  :func:`tool_model`, :func:`holder_model`, :func:`spindle_model` — their beam
  models; :func:`composite_material`; :func:`tool_tip_chain`, :func:`attach`
  — the coupling algebra on arrays; :func:`prediction_grid` — the frequency
  lines of a prediction.

Bending planes: x and y are predicted separately (the tool and holder are
axisymmetric); a spindle side without y terms gives y = x (with a note). A
spindle FRF with x–y cross terms couples the planes: one chain over
(x, θ_x, y, θ_y) (:mod:`jointdb.stack._twoplane`) and a tip FRF with
``H[1x,1y]``, ``H[1y,1x]``.

Node numbers: tip 1, tool at holder face 2, holder nose 3, holder base 4,
spindle nose 5 (:data:`NODES`; :data:`TIP_NODE` = 1). Interfaces: :data:`INTERFACE_NAMES` =
``("tool-holder", "holder-spindle")``; joint FRFs are planar receptances on
``x`` and ``ry`` (any node number), ``u_A − u_B = H_J λ`` with A on the tool
side.

Stack file (JSON, SI units; fields other than these are refused)::

    {
      "format": "jointdb-stack/1",
      "name": "12 mm carbide end mill in a steel chuck",
      "tool": {"material": "carbide", "loss_factor": 0.002,   # optional "fluted_area_ratio": 0.6
               "segments": [{"length": 0.030, "diameter": 0.012, "fluted": true},
                            {"length": 0.050, "diameter": 0.012}]},
      "gauge_length": 0.050,                  # or "insertion_length": 0.030
      "holder": {"material": "steel", "loss_factor": 0.002,
                 "segments": [{"length": 0.040, "outer_diameter": 0.032, "inner_diameter": 0.012},
                              {"length": 0.030, "outer_diameter": 0.050}]},
      "spindle": {"model": {...jointdb.fe model...}, "point": "nose"}
                 | {"file": "spindle.uff", "node": 5},
      "interfaces": {"tool-holder": {"query": {"joint_type": "tool-holder",
                                               "materials": ["steel", "carbide"], "torque_nm": 60}},
                     "holder-spindle": "rigid" | "name@version" | "name@label" | {"k": [kx, kθ], "c": [cx, cθ]}
                                       | {"query": {"joint_type": "holder-spindle", "preload_n": 20000,
                                                    "geometry": {"taper_diameter_m": 0.063}, ...}}},
      "frequency": {"min": 10, "max": 5000, "step": 5}
    }
"""

from jointdb.stack._chain import attach, tool_tip_chain
from jointdb.stack._parts import NODES, TIP_NODE, composite_material, holder_model, tool_model
from jointdb.stack._predict import Prediction, predict_tool_tip, prediction_grid, spindle_model, stack_parts
from jointdb.stack._spec import (
    FORMAT,
    INTERFACE_NAMES,
    KOPS_VO_RATIO,
    FrequencyGrid,
    Holder,
    HolderSegment,
    JointChoice,
    MeasuredSpindle,
    ModelledSpindle,
    StackSpec,
    Tool,
    ToolSegment,
)
from jointdb.stack._stackfile import stack_from_dict, stack_to_dict

__all__ = [
    "FORMAT",
    "INTERFACE_NAMES",
    "KOPS_VO_RATIO",
    "NODES",
    "TIP_NODE",
    "FrequencyGrid",
    "Holder",
    "HolderSegment",
    "JointChoice",
    "MeasuredSpindle",
    "ModelledSpindle",
    "Prediction",
    "StackSpec",
    "Tool",
    "ToolSegment",
    "attach",
    "composite_material",
    "holder_model",
    "predict_tool_tip",
    "prediction_grid",
    "spindle_model",
    "stack_from_dict",
    "stack_to_dict",
    "stack_parts",
    "tool_model",
    "tool_tip_chain",
]
