"""``slam.json`` read back (issue #15 point 4): the summary the slam stage writes (its keys in
DESIGN.md §8 ★), checked field by field before ``evaluate`` or the report use it."""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from radioslam.io.errors import SlamSummaryError
from radioslam.io.json_io import read_json


class LoopRecord(BaseModel):
    model_config = ConfigDict(extra="allow")
    anchor: int = Field(ge=0)
    pose: int = Field(ge=0)
    score: float | None = None


class SlamSummary(BaseModel):
    """The fields other stages read; the rest is kept as written."""

    model_config = ConfigDict(extra="allow", allow_inf_nan=False)
    scan_status: list[str] = []
    status_counts: dict[str, int] = {}
    tracking_lost: bool = False
    lost_scans: list[int] = []
    match_score: list[float | None] = []
    ms_per_scan: list[float | None] = []
    loop_closures: list[LoopRecord] = []
    points_per_scan: list[int] = []
    slam_ms_per_scan_median: float | None = None
    timings_s: dict[str, float | None] = {}
    config: dict = {}


def read_slam_summary(path: str | Path) -> dict:
    """slam.json as a dict, every field other stages read checked; {} when there is none."""
    path = Path(path)
    if not path.exists():
        return {}
    doc = read_json(path, SlamSummaryError)
    if not isinstance(doc, dict):
        raise SlamSummaryError("must be a JSON object", file=path, field="(document)")
    try:
        return SlamSummary.model_validate(doc).model_dump()
    except ValidationError as exc:
        first = exc.errors()[0]
        raise SlamSummaryError(first["msg"], file=path, field=".".join(str(p) for p in first["loc"])) from None
