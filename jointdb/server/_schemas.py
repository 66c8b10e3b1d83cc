"""Request bodies (pydantic): types are checked before anything reaches the repository,
whose own rules (materials, names, labels, model kinds) are then applied unchanged.

What a file kind already describes is not described again: the conditions of a joint are
the campaign file's (:class:`jointdb.schemas.campaign.Conditions`), a stack to predict is
read by the stack file's schema and reader (:func:`jointdb.stack.stack_from_dict`).
"""

from __future__ import annotations

from typing import Any, Literal, Optional

from pydantic import BaseModel, ConfigDict, Field

from jointdb.errors import InputError
from jointdb.schemas.campaign import Conditions as CampaignConditions


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ConditionsIn(CampaignConditions):
    """A joint's conditions, as in a campaign file (materials, torque, preload, geometry, extra).

    Built in Python (a web form's fields), a value out of range is an :class:`InputError`
    naming the field, as the repository's own rules would give.
    """

    def __init__(self, **data: Any) -> None:
        from pydantic import ValidationError

        from jointdb.schemas import describe_error

        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise InputError(f"conditions.{describe_error(exc, 'campaign')}") from None

    def to_conditions(self):
        """The store's :class:`~jointdb.store.Conditions` of these conditions."""
        from jointdb.store import Conditions

        return Conditions(tuple(self.materials or ()), self.preload_n, self.torque_nm, dict(self.geometry or {}),
                          dict(self.extra or {}))


class NearestIn(Strict):
    joint_type: str = Field(..., max_length=100, description="Joint type (types are never mixed).")
    conditions: ConditionsIn = Field(default_factory=ConditionsIn)
    k: int = Field(3, ge=1, le=100, description="Number of nearest versions (a stack prediction asks for 64: the interpolation pool and its leave-one-out neighbours).")
    at: Optional[str] = Field(None, max_length=40, description="Query the catalogue as it was at this ISO time.")
    label: Optional[str] = Field(None, max_length=100, description="Only versions carrying this label.")
    all_versions: bool = Field(False, description="Rank every version, not only the newest of each joint.")
    include_deprecated: bool = Field(False, description="Also rank deprecated versions (excluded by default).")


class CatalogueIn(Strict):
    name: str = Field(..., max_length=200, description="Joint name (new joint, or a new version of it).")
    filename: Optional[str] = Field(None, max_length=200, description="Name of the uploaded file (.h5), kept in "
                                    "provenance.")
    file_b64: Optional[str] = Field(None, description="The identified joint file (HDF5 from `jointdb identify`), "
                                    "base64. Or give `frf` (JSON) with joint_type and model_kind.")
    frf: Optional["FrfIn"] = Field(None, description="The joint FRF as JSON (instead of a file).")
    input_files: dict[str, str] = Field(default_factory=dict, description="With `frf`: file name -> SHA-256.")
    parameters: dict[str, Any] = Field(default_factory=dict, description="With `frf`: method parameters.")
    joint_type: Optional[str] = Field(None, max_length=100)
    model_kind: Optional[str] = Field(None, max_length=50)
    method: Optional[str] = Field(None, max_length=200)
    conditions: ConditionsIn = Field(default_factory=ConditionsIn)
    quality: dict[str, float] = Field(default_factory=dict)
    parent: Optional[int] = Field(None, ge=1)
    label: Optional[str] = Field(None, max_length=100)
    force: bool = Field(False, description="Store the given conditions even where they contradict the values the file "
                        "records, or a defining condition of the joint's previous version (the audit log records it).")
    allow_identical: bool = Field(False, description="Add a version even when the latest one already holds the same "
                                  "FRF and conditions (default: nothing is written, 200 with that version).")


class LabelIn(Strict):
    version: int = Field(..., ge=1, le=2**31 - 1)
    label: str = Field(..., max_length=100)


class DeprecateIn(Strict):
    version: Optional[int] = Field(None, ge=1, le=2**31 - 1, description="Only this version (default: the joint).")
    reason: str = Field("", max_length=2000)
    undo: bool = False


class PredictIn(Strict):
    stack: dict[str, Any] = Field(..., description="A stack description (format jointdb-stack/1, schema "
                                  "docs/schemas/stack.schema.json) with its spindle model inline; read by the stack "
                                  "file reader, whose errors name the field.")


class FrfIn(Strict):
    freq_hz: list[float]
    outputs: list[str]
    inputs: list[str]
    real: list[list[list[float]]]
    imag: list[list[list[float]]]
    quantity: str = "receptance"
    units: Optional[list[list[str]]] = None


class LobesIn(Strict):
    frf: Optional[FrfIn] = Field(None, description="Tool-tip FRF as JSON (as the download's JSON format).")
    joint: Optional[str] = Field(None, max_length=200, description="Or: a catalogued version's FRF, name ...")
    version: Optional[int] = Field(None, ge=1, description="... and version.")
    op: Literal["milling", "turning"] = "milling"
    teeth: int = Field(2, ge=1, le=64)
    kt: Optional[float] = Field(None, gt=0, description="Milling: tangential coefficient [N/m²].")
    kr: Optional[float] = Field(None, ge=0, description="Milling: radial coefficient [N/m²].")
    kf: Optional[float] = Field(None, gt=0, description="Turning: cutting coefficient [N/m²].")
    immersion: float = Field(1.0, gt=0, le=1)
    up: bool = False
    rpm_min: float = Field(2000.0, gt=0)
    rpm_max: float = Field(20000.0, gt=0)
    n_speeds: int = Field(300, ge=2, le=5000)


class LobesJobIn(LobesIn):
    """``POST /api/v1/lobes`` and lobes jobs: the CLI's method, refinement and SD options too."""

    method: Literal["zoa", "sd"] = Field("zoa", description="Milling: zero-order approximation or "
                                         "semi-discretization.")
    refine: int = Field(3, ge=0, le=10, description="Rounds of extra speeds near the lobes' minima and pockets.")
    intervals: int = Field(40, ge=2, le=2000, description="SD: intervals per tooth period.")
    modes: Optional[int] = Field(None, ge=1, le=400, description="SD: modes to fit per direction.")
    band: Optional[list[float]] = Field(None, min_length=2, max_length=2, description="SD: modal-fit band "
                                        "[FMIN, FMAX] in Hz.")
    max_order: int = Field(30, ge=2, le=400, description="SD: highest pLSCF order.")
    cross_terms: Optional[bool] = Field(None, description="ZOA: use the x–y cross FRFs (default: when present).")


class DiagnoseIn(Strict):
    model: dict[str, Any] = Field(..., description="The nominal beam model (as a model file, JSON).")
    recordings: list[FrfIn] = Field(..., min_length=1, max_length=20, description="Recorded FRFs, one per "
                                    "excitation level.")
    map: dict[str, str] = Field(default_factory=dict, description="Recording node -> model point, e.g. "
                                "{\"1\": \"tip\"}.")
    levels: Optional[list[float]] = Field(None, description="Excitation level of each recording [N].")
    band: Optional[list[float]] = Field(None, min_length=2, max_length=2, description="[FMIN, FMAX] in Hz.")
    combinations: bool = Field(True, description="Also fit pairs of explanations.")


class IdentifyIn(Strict):
    filename: str = Field("campaign.zip", max_length=200, description="Name of the campaign archive (.zip).")
    file_b64: str = Field(..., description="The campaign archive (.zip), base64.")
    name: Optional[str] = Field(None, max_length=200, description="Joint name to suggest (default: the "
                                "campaign's name).")
    conditions: ConditionsIn = Field(default_factory=ConditionsIn, description="Conditions from the upload form: "
                                     "contradictions with the campaign's are flagged in the review.")


class JobCatalogueIn(Strict):
    name: Optional[str] = Field(None, max_length=200, description="Joint name (default: the campaign's).")
    label: Optional[str] = Field(None, max_length=100)
    conditions: ConditionsIn = Field(default_factory=ConditionsIn, description="Override / complete the "
                                     "campaign's conditions (a contradiction needs force).")
    parent: Optional[int] = Field(None, ge=1)
    force: bool = False


class TokenIn(Strict):
    name: str = Field(..., max_length=100, description="Owner: recorded in the audit log for the token's writes.")
    role: Literal["reader", "writer", "admin"]
    expires: Optional[str] = Field(None, max_length=40, description="ISO time or a lifetime like 30d, 12h.")


class GcIn(Strict):
    min_age_s: float = Field(3600.0, ge=0)
    dry_run: bool = True


CatalogueIn.model_rebuild()
