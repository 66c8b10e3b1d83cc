"""The pages that do the work, built on the JSON API only: their scripts (``static/flow.js``)
call ``/api/v1`` with the browser session (writes carry the session's CSRF token in
``X-CSRF-Token``, see :func:`jointdb.server._deps.session_identity`).

- ``/ui/upload``: upload a campaign archive → ``POST /api/v1/jobs/identify`` → the job page.
- ``/ui/jobs/{id}``: a job's progress; an identify job's review (k, c ± σ, verdict, fit plots,
  conditions pre-filled, contradictions flagged) → ``POST …/catalogue`` or ``…/discard``.
- ``/ui/design``: a stack from the parts library (``GET /api/v1/parts``) and a tool; the nearest
  joints (``POST /api/v1/query/nearest`` and ``/query/interpolate``); predict as a job; the tip
  FRF of both planes against rigid joints; then lobes as a job (material library, method,
  teeth, immersion) with the best speeds; downloads (CSV, JSON, PNG).
"""

from __future__ import annotations

import json

from fastapi import Request

from jointdb.server.web_core import _handle, _page, _reader, router

#: Cutting-coefficient library of the lobes form: (name, kt, kr in N/mm², source). Only the
#: first is a published identification; the others are guide values to be replaced by a
#: measurement for the tool at hand (the lobes scale with 1/kt).
MATERIALS = (
    ("Aluminium 7075-T6", 796.0, 168.8, "Altintas, Manufacturing Automation, 2nd ed. (2012), milling stability "
                                        "example: Kt = 796 N/mm², Kr = 0.212 Kt"),
    ("Aluminium alloy (guide)", 700.0, 210.0, "guide value: specific cutting force tables for wrought aluminium at "
                                              "0.1–0.2 mm chip thickness; Kr ≈ 0.3 Kt; measure for your tool"),
    ("Steel C45 / AISI 1045 (guide)", 2000.0, 600.0, "guide value: specific cutting force tables for unalloyed "
                                                     "steel at 0.1–0.2 mm chip thickness; Kr ≈ 0.3 Kt; measure"),
    ("Grey cast iron (guide)", 1100.0, 330.0, "guide value: specific cutting force tables for grey cast iron; "
                                              "Kr ≈ 0.3 Kt; measure for your tool"),
    ("Ti-6Al-4V (guide)", 1400.0, 420.0, "guide value: specific cutting force tables for titanium alloys; "
                                         "Kr ≈ 0.3 Kt; measure for your tool"),
)
#: Tool materials of the design form: stack file name -> joint-catalogue material name.
TOOL_MATERIALS = (("carbide", "tungsten-carbide"), ("steel", "steel"))
#: Gauge diameters of the tapers a holder may name (for the holder–spindle joint query).
TAPER_DIAMETERS_M = {"HSK-A63": 0.063, "HSK-A100": 0.1, "BT40": 0.04445, "SK40": 0.04445, "CAT40": 0.04445,
                     "BT30": 0.03175, "HSK-A50": 0.05}


def _json_block(data) -> str:
    return json.dumps(data, separators=(",", ":")).replace("<", "\\u003c")


@router.get("/upload")
@_handle
def upload(request: Request):
    _reader(request)
    return _page(request, "upload.html", title="upload a campaign", with_plots=True)


@router.get("/jobs")
@_handle
def jobs(request: Request):
    _reader(request)
    return _page(request, "jobs.html", title="my jobs", with_plots=True)


@router.get("/jobs/{job_id}")
@_handle
def job(request: Request, job_id: str):
    _reader(request)
    if not (0 < len(job_id) <= 32 and job_id.isalnum()):
        job_id = ""
    return _page(request, "job.html", title="job", job_id=job_id, with_plots=True)


@router.get("/design")
@_handle
def design(request: Request):
    _reader(request)
    library = {"materials": [{"name": n, "kt": kt, "kr": kr, "source": s} for n, kt, kr, s in MATERIALS],
               "tool_materials": [{"stack": a, "catalogue": b} for a, b in TOOL_MATERIALS],
               "tapers": TAPER_DIAMETERS_M}
    return _page(request, "design.html", title="design a stack", library=_json_block(library), with_plots=True)
