"""Result tables as CSV and Markdown (written atomically, side by side)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from radioslam.io.atomic import atomic_write_text


def _cell(v) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def write_table(stem: str | Path, header: list[str], rows: list[list]) -> None:
    """``stem``.csv and ``stem``.md with the same rows."""
    stem = Path(stem)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows([[_cell(v) for v in row] for row in rows])
    atomic_write_text(stem.with_suffix(".csv"), buffer.getvalue())
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(v) for v in row) + " |" for row in rows]
    atomic_write_text(stem.with_suffix(".md"), "\n".join(lines) + "\n")
