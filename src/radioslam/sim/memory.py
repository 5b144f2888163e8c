"""What simulating and sensing one pose will need in memory, estimated before anything is allocated
(issue #15 point 3), so that a radio or scene beyond the machine ends in one line naming the field,
not in a traceback or the kernel's OOM killer.

The estimate counts the largest arrays, each with the number of copies that is alive at once
(measured with ``tracemalloc``, ``tests/test_memory_budget.py``):
- the capture's samples, complex64, beams × window: 3 copies while synthesizing (peak 2.0–2.4× on
  paper-cnv and on longer windows), 4 while sensing a recording (the file read, then the
  receiver's peak below 2×);
- the echo paths' beam gains, complex128, paths × beams, twice (the gains and their product with the
  amplitudes); the paths of the channel backend (:func:`expected_paths`): the flat caster's rays × hits;
  the 2.5D caster's (elevation rows) rays × hits × rows and the floor's and ceiling's fan; Sionna RT's
  ``SIONNA_PATHS_PER_SAMPLE`` per diffuse sample and orientation (more in a closed room);
- the ray caster's (rays × segments) float64 tables, about 10 alive at once, in blocks of at most
  ``TABLE_CELLS`` cells (:mod:`radioslam.scene.raycast`), and the 2.5D caster's (rays × hits) × elevation
  quadrature tables (:mod:`radioslam.sim.elevated`);
- Sionna RT's own trace (Dr.Jit's buffers, outside Python's allocator): ``SIONNA_TRACE_BASE`` plus
  ``SIONNA_BYTES_PER_SAMPLE`` per diffuse sample, measured as resident memory on sionna-rt 2.2's CPU
  backend (paper-cnv extruded, a concrete floor and ceiling, 5·10⁴ – 8·10⁵ samples: 0.77 – 5.9 GB a trace,
  0.32 paths per sample and orientation; docs/notes.md, session 26).

Poses are simulated one at a time, so a walk needs what one pose needs.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from radioslam.choices import ChannelKind
from radioslam.scene.raycast import TABLE_CELLS
from radioslam.sim.errors import SimulationError

SAMPLE_COPIES_SIMULATE = 3
SAMPLE_COPIES_SENSE = 4
GAIN_COPIES = 2
RAY_TABLES = 10
QUADRATURE_TABLES = 8  # the 2.5D caster's (columns × cells) float64 tables alive at once
QUADRATURE_CELLS = 720  # its elevation quadrature: 180° / WALL_STEP_DEG
SIONNA_TRACE_BASE = 500 * 2**20
SIONNA_BYTES_PER_SAMPLE = 8 * 2**10
# Sionna's paths per diffuse sample and orientation, with no floor or ceiling (0.053 measured on the extruded
# paper-cnv: the rays up and down escape) and in a closed room (0.32 with both), and in between for one
SIONNA_PATHS_PER_SAMPLE = (0.1, 0.4)


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


def expected_paths(radio, channel: ChannelKind = ChannelKind.BUILTIN, planes: int = 0) -> tuple[int, str]:
    """How many echo paths one pose gives (at most, or for Sionna as measured), and the field that drives
    it; ``planes`` is the number of the scene's floor and ceiling (0 … 2; a Mitsuba scene counts as 2)."""
    if ChannelKind(channel) is ChannelKind.SIONNA:
        open_room, closed = SIONNA_PATHS_PER_SAMPLE
        per_sample = open_room + (closed - open_room) * planes / 2
        return math.ceil(per_sample * radio.sionna_samples * radio.orientations), "radio.sionna_samples"
    columns = math.ceil(360.0 / radio.ray_spacing_deg) * radio.max_hits
    if radio.elevation_beams == 1:
        return columns, "radio.ray_spacing_deg"
    fan = math.ceil(360.0 / radio.ray_spacing_3d_deg) * math.ceil(90.0 / radio.ray_spacing_3d_deg)
    return columns * radio.elevation_beams + planes * fan, "radio.ray_spacing_deg × radio.elevation_beams"


def pose_memory(beams: int, window_samples: int, radio, segments: int, sensing: bool = False,
                channel: ChannelKind = ChannelKind.BUILTIN, planes: int = 0) -> MemoryEstimate:
    """One pose's simulation (or, ``sensing``, the sensing of its recording) in bytes, its paths from the
    backend ``channel`` (and an extrusion's ``planes``)."""
    samples = beams * window_samples * 8
    if sensing:
        return MemoryEstimate({"samples": (SAMPLE_COPIES_SENSE * samples, "radio.fft_size × symbols × beams")})
    rays = math.ceil(360.0 / radio.ray_spacing_deg)
    paths, paths_field = expected_paths(radio, channel, planes)
    parts = {
        "samples": (SAMPLE_COPIES_SIMULATE * samples, "radio.fft_size × symbols × beams"),
        "path gains": (GAIN_COPIES * paths * beams * 16, paths_field),
        "ray tables": (RAY_TABLES * min(rays * max(segments, 1), TABLE_CELLS) * 8, "walls × radio.ray_spacing_deg"),
    }
    if ChannelKind(channel) is ChannelKind.SIONNA:
        parts["ray tracer"] = (SIONNA_TRACE_BASE + SIONNA_BYTES_PER_SAMPLE * radio.sionna_samples,
                               "radio.sionna_samples")
    elif radio.elevation_beams > 1:
        parts["elevation quadrature"] = (QUADRATURE_TABLES * rays * radio.max_hits * QUADRATURE_CELLS * 8,
                                         "radio.ray_spacing_deg")
    return MemoryEstimate(parts)


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
