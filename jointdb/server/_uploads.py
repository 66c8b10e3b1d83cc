"""Campaign archives and HDF5 files uploaded to the service: the checks live in
:mod:`jointdb.io._uploads` (the job workers unpack uploads too, below the server)."""

from jointdb.io._uploads import (  # noqa: F401 - the server's names for them
    MAX_MEMBERS,
    MAX_RATIO,
    MAX_TOTAL_BYTES,
    RATIO_FREE_BYTES,
    check_hdf5_self_contained,
    unpack_campaign,
)
