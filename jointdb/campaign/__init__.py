"""Measurement campaigns: the application layer of ``identify`` and ``couple``.

A campaign file (JSON, ``jointdb-campaign/1``) names substructures, the
interface, the measured assembly files and the joint model (format in
:mod:`jointdb.campaign._file`). This package reads and checks it, runs the
identification (:mod:`jointdb.coupling`) and forward coupling, and is shared by
the CLI (``jointdb identify``, ``jointdb couple``, ``jointdb catalogue``) and by
:mod:`jointdb.usecases`. It spans files and numerics, so it lives outside both the
numerical core and the CLI.

Campaign files
--------------
   load_campaign      -- read and check a campaign file (structure, names, DOFs, files exist)
   Campaign           -- a parsed, checked campaign (no FRFs loaded yet)
   Substructure       -- one substructure of a campaign: name, kind, file, DOFs
   file_hashes        -- SHA-256 of the campaign file and of every file it names

Identification and coupling
---------------------------
   identify_campaign  -- identify the joint, re-couple, fit constant (k, c), validate
   IdentifyOutcome    -- what :func:`identify_campaign` found (joint, reconstruction, verdicts)
   couple_campaign    -- couple the substructures with a joint; compare with measurements

Joint exchange files
--------------------
   joint_attrs        -- metadata stored with the joint FRF in the HDF5 exchange file
   load_joint_file    -- a joint FRF written by ``jointdb identify`` and its model kind
"""

from jointdb.campaign._file import Campaign, Substructure, file_hashes, load_campaign
from jointdb.campaign._run import (
    IdentifyOutcome,
    couple_campaign,
    identify_campaign,
    joint_attrs,
    load_joint_file,
)

__all__ = [
    "Campaign",
    "Substructure",
    "file_hashes",
    "load_campaign",
    "IdentifyOutcome",
    "identify_campaign",
    "couple_campaign",
    "joint_attrs",
    "load_joint_file",
]
