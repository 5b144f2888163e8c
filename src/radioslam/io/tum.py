"""TUM trajectory files: ``t x y z qx qy qz qw`` per line (planar poses: z = 0, yaw quaternion)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radioslam.io.atomic import atomic_write_text
from radioslam.io.errors import TumError


def write_tum(path: str | Path, timestamps: np.ndarray, poses: np.ndarray) -> None:
    """Write SE(2) poses (P, 3) as a TUM file (atomically); NaN x and y write ``nan`` (a gyro's
    odometry: its turns measured, its translation unknown)."""
    poses = np.asarray(poses, dtype=np.float64)
    half = poses[:, 2] / 2.0
    zeros = np.zeros(len(poses))
    rows = np.column_stack([timestamps, poses[:, 0], poses[:, 1], zeros, zeros, zeros,
                            np.sin(half), np.cos(half)])
    lines = "\n".join(" ".join(f"{v:.9f}" for v in row) for row in rows)
    atomic_write_text(path, "# timestamp x y z qx qy qz qw\n" + lines + "\n")


def _numeric_rows(path: Path, count: int, split, names: str, nan_columns: slice = slice(0, 0)) -> np.ndarray:
    """The rows (N, ``count``) of a text file of numbers, ``split`` cutting a line into fields; blank lines,
    ``#`` comments and a first line starting with ``names``' first word skipped. NaN is allowed only in
    ``nan_columns``, infinity nowhere; any other line is a :class:`TumError` naming it."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TumError("no such file", file=path, field="(file)") from None
    header, rows = names.split()[0].lower(), []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = [f.strip() for f in split(line)]
        if not line.strip() or line.lstrip().startswith("#") or (not rows and fields[0].lower() == header):
            continue
        if len(fields) != count:
            raise TumError(f"expected {count} numbers ({names}), got {len(fields)}", file=path, field=f"line {number}")
        try:
            values = np.array([float(v) for v in fields])
        except ValueError:
            raise TumError("not a number", file=path, field=f"line {number}") from None
        known = np.delete(values, np.arange(count)[nan_columns])
        if not np.all(np.isfinite(known)) or np.any(np.isinf(values)):
            raise TumError("NaN or infinite value", file=path, field=f"line {number}")
        rows.append(values)
    return np.array(rows).reshape(-1, count)


def read_tum(path: str | Path, unknown_translation: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM file: timestamps (P,) and SE(2) poses (P, 3), yaw from the quaternion. With
    ``unknown_translation`` a file whose x and y are ``nan`` on every line (a gyro's odometry) is read too."""
    path = Path(path)
    data = _numeric_rows(path, 8, str.split, "timestamp x y z qx qy qz qw",
                         slice(1, 3) if unknown_translation else slice(0, 0))
    if not len(data):
        raise TumError("no poses", file=path, field="(file)")
    if unknown_translation and np.isnan(data[:, 1:3]).any() and not np.isnan(data[:, 1:3]).all():
        raise TumError("x and y must be nan on every line (a gyro's odometry) or on none", file=path, field="x, y")
    qx, qy, qz, qw = data[:, 4:8].T
    yaw = np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy**2 + qz**2))
    return data[:, 0], np.column_stack([data[:, 1], data[:, 2], yaw])


def read_angular_rate(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """An IMU's angular rate about z: a CSV of ``timestamp,wz`` (s, rad/s) per line, ``#`` comments and a
    header line of names allowed. Returns timestamps (N,) increasing and rates (N,)."""
    path = Path(path)
    data = _numeric_rows(path, 2, lambda line: line.split(","), "timestamp wz")
    if len(data) < 2:
        raise TumError("fewer than 2 samples", file=path, field="(file)")
    if np.any(np.diff(data[:, 0]) <= 0):
        raise TumError("timestamps must increase", file=path, field="timestamp")
    return data[:, 0], data[:, 1]


def headings_at(timestamps: np.ndarray, rate_times: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """The heading (P,) at each of ``timestamps``: the angular rate integrated by the trapezoid rule from the
    first timestamp (heading 0 there), linearly interpolated between samples."""
    turned = np.concatenate([[0.0], np.cumsum(0.5 * (rates[1:] + rates[:-1]) * np.diff(rate_times))])
    heading = np.interp(timestamps, rate_times, turned)
    return heading - heading[0]
