"""Measurement campaigns: the application layer of ``identify`` and ``couple``.

A campaign file (JSON, ``jointdb-campaign/1``) names substructures, the
interface, the measured assembly files and the joint model (format in
:mod:`jointdb.campaign._file`). This package reads and checks it, runs the
identification (:mod:`jointdb.coupling`) and forward coupling, and is shared by
the CLI (``jointdb identify``, ``jointdb couple``, ``jointdb catalogue``) and by
:mod:`jointdb.usecases`. It spans files and numerics, so it lives outside both the
numerical core and the CLI.
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
