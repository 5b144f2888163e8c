"""What simulating and sensing one pose will need in memory, estimated before anything is allocated
(issue #15 point 3), so that a radio or scene beyond the machine ends in one line naming the field,
not in a traceback or the kernel's OOM killer.

The estimate counts the largest arrays, each with the number of copies that is alive at once
(measured with ``tracemalloc``, ``tests/test_memory_budget.py``):
- the capture's samples, complex64, beams × window: 3 copies while synthesizing (peak 2.0–2.4× on
  paper-cnv and on longer windows), 4 while sensing a recording (the file read, then the
  receiver's peak below 2×);
- the echo paths' beam gains, complex128, (rays × hits) × beams, twice (gains and their sorted copy);
- the ray caster's (rays × segments) float64 tables, about 10 alive at once, in blocks of at most
  ``TABLE_CELLS`` cells (:mod:`radioslam.scene.raycast`).

Poses are simulated one at a time, so a walk needs what one pose needs.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from radioslam.scene.raycast import TABLE_CELLS
from radioslam.sim.errors import SimulationError

SAMPLE_COPIES_SIMULATE = 3
SAMPLE_COPIES_SENSE = 4
GAIN_COPIES = 2
RAY_TABLES = 10


@dataclass(frozen=True)
class MemoryEstimate:
    """Bytes per component of one pose, and the configuration field each comes from."""

    parts: dict[str, tuple[int, str]]  # name → (bytes, the field that drives it)

    @property
    def total(self) -> int:
        return sum(b for b, _ in self.parts.values())

    @property
    def largest(self) -> tuple[str, int, str]:
        name = max(self.parts, key=lambda k: self.parts[k][0])
        return name, *self.parts[name]


def machine_memory() -> int:
    """Physical memory of this machine, bytes (0 where the platform does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 0


def default_budget() -> int:
    """Half the machine's memory (2 GiB where it cannot be read)."""
    return machine_memory() // 2 or 2 * 2**30


def pose_memory(beams: int, window_samples: int, radio, segments: int, sensing: bool = False) -> MemoryEstimate:
    """One pose's simulation (or, ``sensing``, the sensing of its recording) in bytes."""
    samples = beams * window_samples * 8
    if sensing:
        return MemoryEstimate({"samples": (SAMPLE_COPIES_SENSE * samples, "radio.fft_size × symbols × beams")})
    rays = math.ceil(360.0 / radio.ray_spacing_deg)
    return MemoryEstimate({
        "samples": (SAMPLE_COPIES_SIMULATE * samples, "radio.fft_size × symbols × beams"),
        "path gains": (GAIN_COPIES * rays * radio.max_hits * beams * 16, "radio.ray_spacing_deg"),
        "ray tables": (RAY_TABLES * min(rays * max(segments, 1), TABLE_CELLS) * 8, "walls × radio.ray_spacing_deg"),
    })


def recording_memory(data_bytes: int) -> MemoryEstimate:
    """Sensing one recording of ``data_bytes`` of complex64 samples."""
    return MemoryEstimate({"samples": (SAMPLE_COPIES_SENSE * data_bytes, "core:sample_count")})


def check_budget(estimate: MemoryEstimate, budget: int, file: str | None) -> None:
    """Raise :class:`SimulationError` naming the largest part's field when ``estimate`` exceeds ``budget``."""
    if estimate.total <= budget:
        return
    name, size, field = estimate.largest
    raise SimulationError(f"needs ≈ {estimate.total / 2**30:.2f} GiB ({name} {size / 2**30:.2f} GiB), "
                          f"more than the memory budget of {budget / 2**30:.2f} GiB (--max-memory)",
                          file=file, field=field)
