"""``calibration.json``: the hardware-delay estimate of eq. (11) and the targets it used."""

from __future__ import annotations

from pathlib import Path

from radioslam.io.atomic import atomic_write_text
from radioslam.io.errors import CalibrationFileError
from radioslam.io.json_io import dumps, read_json
from radioslam.sensing.calibration import Calibration, CalibrationTarget
from radioslam.sensing.leakage import LeakageModel


def write_calibration(path: str | Path, calibration: Calibration) -> None:
    atomic_write_text(path, dumps(calibration.to_dict(), indent=2) + "\n")


def read_calibration(path: str | Path) -> Calibration:
    path = Path(path)
    if not path.exists():
        raise CalibrationFileError("no such file; run 'radioslam calibrate' (or 'simulate') first",
                                   file=path, field="(file)")
    doc = read_json(path, CalibrationFileError)
    if not isinstance(doc, dict):
        raise CalibrationFileError("must be a JSON object", file=path, field="(document)")
    delay = doc.get("hardware_delay_s") if isinstance(doc, dict) else None
    if not isinstance(delay, (int, float)) or isinstance(delay, bool) or not 0 <= delay < 1e-3:
        raise CalibrationFileError("must be a number of seconds in [0, 1 ms)", file=path, field="hardware_delay_s")
    try:
        targets = [CalibrationTarget(float(t["range_m"]), float(t["t1_s"]), float(t["t2_s"]), float(t["ota_s"]))
                   for t in doc.get("targets", [])]
    except (KeyError, TypeError, ValueError) as exc:
        raise CalibrationFileError(f"malformed target: {exc}", file=path, field="targets") from None
    leakage = None
    if doc.get("leakage") is not None:
        try:
            leakage = LeakageModel.from_dict(doc["leakage"])
        except ValueError as exc:
            field, _, reason = str(exc).partition(": ")
            raise CalibrationFileError(reason, file=path, field=field) from None
    return Calibration(float(delay), targets, str(doc.get("source", "")), leakage)
