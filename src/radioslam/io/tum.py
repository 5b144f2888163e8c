"""TUM trajectory files: ``t x y z qx qy qz qw`` per line (planar poses: z = 0, yaw quaternion)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radioslam.io.atomic import atomic_write_text
from radioslam.io.errors import TumError


def write_tum(path: str | Path, timestamps: np.ndarray, poses: np.ndarray) -> None:
    """Write SE(2) poses (P, 3) as a TUM file (atomically)."""
    poses = np.asarray(poses, dtype=np.float64)
    half = poses[:, 2] / 2.0
    zeros = np.zeros(len(poses))
    rows = np.column_stack([timestamps, poses[:, 0], poses[:, 1], zeros, zeros, zeros,
                            np.sin(half), np.cos(half)])
    lines = "\n".join(" ".join(f"{v:.9f}" for v in row) for row in rows)
    atomic_write_text(path, "# timestamp x y z qx qy qz qw\n" + lines + "\n")


def read_tum(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM file: timestamps (P,) and SE(2) poses (P, 3), yaw from the quaternion."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TumError("no such file", file=path, field="(file)") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split()
        if len(fields) != 8:
            raise TumError(f"expected 8 numbers, got {len(fields)}", file=path, field=f"line {number}")
        try:
            values = [float(v) for v in fields]
        except ValueError:
            raise TumError("not a number", file=path, field=f"line {number}") from None
        if not np.all(np.isfinite(values)):
            raise TumError("NaN or infinite value", file=path, field=f"line {number}")
        rows.append(values)
    if not rows:
        raise TumError("no poses", file=path, field="(file)")
    data = np.array(rows)
    qx, qy, qz, qw = data[:, 4:8].T
    yaw = np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy**2 + qz**2))
    return data[:, 0], np.column_stack([data[:, 1], data[:, 2], yaw])
