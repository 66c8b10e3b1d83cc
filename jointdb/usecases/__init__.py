"""The application layer: the use cases the CLI, the HTTP service and the demo call.

Named for what it holds — use cases, as plain functions over typed inputs — and placed
between the store / io / numeric core below and the shells above (``jointdb.cli``,
``jointdb.server``): a shell parses its input, calls one use case and renders the answer;
the logic lives here, once, so the CLI and the service cannot drift apart (they import
this package, never each other). Measurement campaigns (reading, identification,
coupling) are the sibling package :mod:`jointdb.campaign`; the demo's job is
:mod:`jointdb._journey`, which calls these functions.

Campaigns (:mod:`jointdb.usecases._catalogue`; planning a campaign is :func:`jointdb.campaign._plan.plan_campaign`)
    identify              -- read, check and identify a campaign file (IRC)
Catalogue (:mod:`jointdb.usecases._catalogue`; one path, one provenance rule)
    catalogue_inputs      -- a campaign or identified joint file -> the catalogue's arguments
    read_joint_file       -- what a joint / campaign file holds (:class:`JointSource`)
    merge_conditions      -- the file's conditions completed by the caller's
    catalogue_campaign    -- identify a campaign and catalogue it (the demo; :class:`CatalogueOutcome`)
Stacks (:mod:`jointdb.usecases._stack`)
    resolve_joints        -- each interface's joint from the catalogue (:class:`JointResolution`)
    predict_stack         -- resolve, then predict the tool-tip FRF (:class:`StackPrediction`)
    predict_with_joints   -- predict the tool-tip FRF with joints already resolved
Lobes (:mod:`jointdb.usecases._lobes`)
    stability_lobes       -- milling (ZOA) or turning lobes of a tool-tip FRF over a speed grid
Parts (:mod:`jointdb.usecases._parts`, :mod:`jointdb.usecases._partfiles`; spindles, holders, tools as catalogued records)
    resolve_stack_parts   -- a stack document's ``{"part": "name@version"}`` references made inline
    stack_from_document   -- a stack document (parts resolved, recorded in ``spec.parts``) -> StackSpec
    part_from_files       -- what ``jointdb parts add`` reads: model / FRF / stack / part files
    add_part_from_files   -- read and catalogue a part
    catalogue_bundled_parts -- the bundled example stack's spindles, holder and tool (the demo does it)
Files (:mod:`jointdb.usecases._files`)
    load_stack            -- a stack file with the spindle FRF / model file it names
    read_frf_file, write_frf_file, frf_format -- FRF files by suffix (UFF58, HDF5, CSV)
    write_joint_file      -- the HDF5 joint exchange file of ``jointdb identify``
"""

from jointdb.usecases._catalogue import (
    CatalogueOutcome,
    JointSource,
    catalogue_campaign,
    catalogue_inputs,
    identify,
    merge_conditions,
    read_joint_file,
)
from jointdb.usecases._files import (
    FRF_SUFFIXES,
    MODEL_KINDS,
    frf_format,
    load_stack,
    read_frf_file,
    write_frf_file,
    write_joint_file,
)
from jointdb.usecases._lobe_report import best_speeds, coefficients_si, lobe_summary, lobes_report
from jointdb.usecases._lobes import stability_lobes
from jointdb.usecases._partfiles import (
    BUNDLED_PARTS,
    PartInput,
    add_part_from_files,
    catalogue_bundled_parts,
    part_from_files,
)
from jointdb.usecases._parts import part_refs, resolve_stack_parts, stack_from_document
from jointdb.usecases._stack import (
    INTERPOLATION_POOL,
    JointResolution,
    StackPrediction,
    predict_stack,
    predict_with_joints,
    resolve_joints,
)

__all__ = [
    "CatalogueOutcome",
    "JointSource",
    "catalogue_campaign",
    "catalogue_inputs",
    "identify",
    "merge_conditions",
    "read_joint_file",
    "FRF_SUFFIXES",
    "MODEL_KINDS",
    "frf_format",
    "load_stack",
    "read_frf_file",
    "write_frf_file",
    "write_joint_file",
    "stability_lobes",
    "lobes_report",
    "lobe_summary",
    "best_speeds",
    "coefficients_si",
    "BUNDLED_PARTS",
    "PartInput",
    "catalogue_bundled_parts",
    "add_part_from_files",
    "part_from_files",
    "part_refs",
    "resolve_stack_parts",
    "stack_from_document",
    "INTERPOLATION_POOL",
    "JointResolution",
    "StackPrediction",
    "predict_stack",
    "predict_with_joints",
    "resolve_joints",
]
