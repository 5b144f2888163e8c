"""The shape of a radioslam SigMF ``.sigmf-meta`` (issue #15 point 4): every field the reader uses,
typed, before any of it is used, so that a wrong shape (an array for the document, ``annotations: 5``,
a string where a number belongs, a pose index of −1 or 1.7) is one error naming the field."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt, ValidationError

from radioslam.io.errors import SigMFError

NS = "radioslam"
Number = Annotated[float, Field(allow_inf_nan=False, strict=False)]
Count = Annotated[StrictInt, Field(ge=0)]


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow", populate_by_name=True)


class GlobalFields(_Open):
    sample_rate: Number = Field(alias="core:sample_rate", gt=0)
    datatype: str = Field(alias="core:datatype")
    pose_index: Count = Field(alias=f"{NS}:pose_index", le=99_999_999)
    window_samples: StrictInt = Field(alias=f"{NS}:window_samples", gt=0, le=2**24)
    radio: dict | None = Field(None, alias=f"{NS}:radio")


class BeamAnnotation(_Open):
    sample_start: Count = Field(alias="core:sample_start")
    sample_count: Count = Field(alias="core:sample_count")
    orientation: Count = Field(alias=f"{NS}:orientation")
    beam_index: StrictInt = Field(alias=f"{NS}:beam_index")
    beam_angle_rad: Number = Field(alias=f"{NS}:beam_angle_rad", ge=-7, le=7)
    ssb_index: Count = Field(alias=f"{NS}:ssb_index")
    symbol_indices: list[Count] = Field(alias=f"{NS}:symbol_indices")
    tx_bits: str = Field(alias=f"{NS}:tx_bits")
    beam_elevation_rad: Number = Field(0.0, alias=f"{NS}:beam_elevation_rad", ge=-2, le=2)
    elevation_index: StrictInt = Field(0, alias=f"{NS}:elevation_index")


class CaptureMeta(_Open):
    global_: GlobalFields = Field(alias="global")
    captures: list[dict] = []
    annotations: list[BeamAnnotation]


def check_meta(meta: object, path: Path) -> None:
    """Raise :class:`SigMFError` naming the first field of ``meta`` that has the wrong shape."""
    if not isinstance(meta, dict):
        raise SigMFError("must be a JSON object (global, captures, annotations)", file=path, field="(document)")
    try:
        CaptureMeta.model_validate(meta)
    except ValidationError as exc:
        first = exc.errors()[0]
        loc = [str(p) for p in first["loc"]]
        where = loc[0] + "".join(f"[{p}]" if p.isdigit() else f".{p}" for p in loc[1:]) if loc else "(document)"
        reason = "required field is missing" if first["type"] == "missing" else first["msg"]
        raise SigMFError(reason, file=path, field=where) from None
